"""Print the MuJoCo softness study (default vs stiffened constraints) as Markdown.

Run: /work/venv/bin/python benchmarks/bench_mujoco_stiffness.py
"""

from sim_models.mujoco.study import markdown_table, stiffness_study

if __name__ == "__main__":
    print(markdown_table(stiffness_study()))

"""Print the MuJoCo softness study (default vs stiffened constraints) as Markdown,
on seeds E1 and E2 (frictionless) from the built-in case files.

Run: /work/venv/bin/python benchmarks/bench_mujoco_stiffness.py
"""

from compare.casefile import builtin_case_files, load_cases
from sim_models.mujoco.study import markdown_table, stiffness_study

SEEDS = ("seed-E1-as-stated", "seed-E2-frictionless")

if __name__ == "__main__":
    cases = {c.name: c for c in load_cases(*builtin_case_files())}
    print(markdown_table(stiffness_study([cases[name] for name in SEEDS])))

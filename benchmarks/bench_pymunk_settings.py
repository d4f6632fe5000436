"""Print the pymunk solver-setting study (force error vs iterations, dt, error bias) as Markdown.

Run: /work/venv/bin/python benchmarks/bench_pymunk_settings.py
"""

from __future__ import annotations

from sim_models.pymunk.study import markdown, settings_study

if __name__ == "__main__":
    print(markdown(settings_study()))

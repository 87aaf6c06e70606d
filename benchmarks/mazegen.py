"""Maze generator benchmark: braiding must not make generation quadratic.

Generates a ``--size`` x ``--size`` maze (corridor 1) with braid 0 and with braid ``--braid``,
each ``--repeats`` times in a fresh process (CPU seconds of the process minus an import-only
process), alternating the two, and reports the medians and their ratio. Target (issue 12):
braid 0.1 at most 2x the time of braid 0 at 1024 x 1024.

With ``--baseline`` the code of the baseline commit (``benchmarks/_common.py``) is measured the
same way once, for comparison (its braiding was quadratic: minutes at 1024 x 1024).

Run: ``.venv/bin/python benchmarks/mazegen.py`` (about a minute). Writes
``benchmarks/results/mazegen.json``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _common import baseline_source, median, run_child, write_report

GENERATE = (
    "import sys, importlib\n"
    "mod = importlib.import_module(sys.argv[1])\n"
    "size, braid = int(sys.argv[2]), float(sys.argv[3])\n"
    "if braid >= 0: mod.generate_maze(size, size, braid=braid, seed=7)\n"
)


def measure(module: str, size: int, braid: float, src: Path | None = None) -> float:
    """CPU seconds of one generation (a process that only imports is subtracted)."""
    cpu, _, _ = run_child(["-c", GENERATE, module, str(size), str(braid)], src=src)
    idle, _, _ = run_child(["-c", GENERATE, module, str(size), "-1"], src=src)
    return max(0.0, cpu - idle)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--size", type=int, default=1024)
    parser.add_argument("--braid", type=float, default=0.1)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--baseline", action="store_true", help="also time the baseline commit")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    module = "selfrepair.world.mazegen"
    plain, braided = [], []
    for i in range(args.repeats):
        plain.append(measure(module, args.size, 0.0))
        braided.append(measure(module, args.size, args.braid))
        print(f"  run {i + 1}: braid 0 {plain[-1]:.2f} s, braid {args.braid} {braided[-1]:.2f} s")
    ratio = median(braided) / median(plain)
    report = {
        "settings": {"size": args.size, "braid": args.braid, "repeats": args.repeats},
        "braid0_cpu_s": plain,
        "braided_cpu_s": braided,
        "median_braid0_cpu_s": median(plain),
        "median_braided_cpu_s": median(braided),
        "ratio": ratio,
        "target_ratio_at_most": 2.0,
        "met": ratio <= 2.0,
    }
    print(
        f"{args.size}x{args.size}: braid 0 {median(plain):.2f} s, braid {args.braid} "
        f"{median(braided):.2f} s (CPU, medians): ratio {ratio:.2f} (target <= 2)"
    )
    if args.baseline:
        src = baseline_source()
        old_plain = measure("selfrepair.mazegen", args.size, 0.0, src)
        old_braided = measure("selfrepair.mazegen", args.size, args.braid, src)
        report["baseline"] = {
            "braid0_cpu_s": old_plain,
            "braided_cpu_s": old_braided,
            "ratio": old_braided / old_plain,
        }
        print(
            f"baseline: braid 0 {old_plain:.2f} s, braid {args.braid} {old_braided:.2f} s: "
            f"ratio {old_braided / old_plain:.2f}"
        )
    print(f"wrote {write_report('mazegen', report, args.out)}")


if __name__ == "__main__":
    main()

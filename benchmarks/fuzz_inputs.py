"""How the command line holds up against hostile input: mutated scene files and spoilt command
lines by the thousand, and what became of each. Its table is in docs/robustness.md.

    python benchmarks/fuzz_inputs.py [--examples 2000] [--seed 0] [--time-limit 10] [--keep DIR]

The cases come from the strategies of tests/fuzz_strategies.py, which the test suite runs a
few of (tests/test_fuzz_inputs.py): half are bundled scenes with one field mutated, spread
evenly over the kinds of mutation; half are command lines with one option spoilt, spread
evenly over every option of every subcommand. Each runs in-process, at 8x6 pixels, under the
referee of tests/fuzz_runner.py. The report gives the count of inputs tried, a table of
outcomes per kind of mutation, the time per case, and one line per class of failure (what
broke, where, how often) with a command that reproduces it; ``--keep DIR`` keeps every case's
folder (its scene.toml and outputs) so that those commands can be rerun.
"""

from __future__ import annotations

import argparse
import collections
import os
import platform
import re
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from fuzz_runner import OUTCOMES, PASSED, run_examples  # noqa: E402
from fuzz_strategies import (SCENE_MUTATIONS, option_cases, option_targets,  # noqa: E402
                             scene_cases)

COLUMNS = {"rendered": "ok", "refused": "refused in one line", "traceback": "traceback",
           "hang": "hang", "partial file": "partial file", "non-finite output": "NaN/inf out",
           "warning": "warning", "bad error line": "bad error line", "not refused": "not refused"}


def failure_class(case, result) -> str:
    """What broke, without the particulars of one input: the outcome, the command, and the
    exception and where (a traceback), the option (a file), or the problem in words."""
    command = " ".join(case.argv[:2]) if case.argv[:1] == ("bench",) else case.argv[0]
    detail = re.sub(r"\(/tmp[^)]*\)|/tmp\S*|\d+(\.\d+)?(e[-+]?\d+)?", "N", result.detail)
    if result.outcome == "traceback":
        kind = detail.split(":")[0]
        place = re.sub(r":N ", " ", detail.rsplit("(in ", 1)[-1].rstrip(")"))
        return f"traceback {kind} in {place}"
    if result.outcome == "hang":
        return f"hang: {command} [{case.kind}]"
    if result.outcome == "partial file":
        return f"partial file: {command} [{case.kind}]"
    return f"{result.outcome}: {command}: {detail[:90]}"


def table(results, kinds) -> list[str]:
    """Markdown: one row per kind of mutation, one column per outcome, then the totals."""
    counts = collections.defaultdict(collections.Counter)
    for case, result, _ in results:
        counts[case.kind][result.outcome] += 1
    head = ["kind of mutation", "tried"] + [COLUMNS[o] for o in OUTCOMES]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    total = collections.Counter()
    for kind in kinds:
        if counts[kind]:
            row = counts[kind]
            total += row
            lines.append(f"| {kind} | {sum(row.values())} | "
                         + " | ".join(str(row[o]) for o in OUTCOMES) + " |")
    lines.append(f"| **all** | **{sum(total.values())}** | "
                 + " | ".join(f"**{total[o]}**" for o in OUTCOMES) + " |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=2000, help="cases to try, about")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--time-limit", type=float, default=10.0,
                        help="seconds before a case counts as a hang")
    parser.add_argument("--keep", type=Path, help="keep every case's folder under DIR")
    args = parser.parse_args()

    targets = option_targets()
    per_kind = max(1, args.examples // 2 // len(SCENE_MUTATIONS))
    per_option = max(1, args.examples // 2 // len(targets))
    folder = args.keep or Path(tempfile.mkdtemp(prefix="marchlab-fuzz-"))
    results, start, done = [], time.perf_counter(), collections.Counter()

    def progress(case, result):
        done[result.outcome] += 1
        print(f"\r{sum(done.values())} cases, {time.perf_counter() - start:.0f} s, "
              f"{sum(done.values()) - done['rendered'] - done['refused']} broke the promise",
              end="", file=sys.stderr, flush=True)

    jobs = [(kind, scene_cases(kind, time_limit=args.time_limit), per_kind)
            for kind in SCENE_MUTATIONS]
    jobs += [(f"{c} {o}", option_cases(c, o, time_limit=args.time_limit), per_option)
             for c, o in targets]
    for number, (name, strategy, count) in enumerate(jobs):
        where = folder / f"{number:03d}-{re.sub(r'[^A-Za-z0-9]+', '-', name)}"
        results += run_examples(strategy, where, count, seed=args.seed, on_result=progress)
    seconds = time.perf_counter() - start
    print(file=sys.stderr)

    times = sorted(r.seconds for _, r, _ in results)
    scene_kinds = list(SCENE_MUTATIONS)
    option_kinds = list(dict.fromkeys(c.kind for c, _, _ in results
                                      if c.kind not in SCENE_MUTATIONS))
    print(f"`python benchmarks/fuzz_inputs.py --examples {args.examples} --seed {args.seed} "
          f"--time-limit {args.time_limit:g}`: {len(results)} inputs tried in {seconds:.0f} s "
          f"on {os.cpu_count()} cores ({platform.machine()}, Python "
          f"{platform.python_version()})\n")
    print("Scene files (a bundled scene with one field mutated):\n")
    print("\n".join(table(results, scene_kinds)))
    print("\nCommand lines (one option of one subcommand spoilt):\n")
    print("\n".join(table(results, option_kinds)))
    print(f"\nTime per case: median {times[len(times) // 2]:.3f} s, 95th percentile "
          f"{times[int(len(times) * 0.95)]:.3f} s, longest {times[-1]:.1f} s "
          f"(limit {args.time_limit:g} s)")

    classes = collections.defaultdict(list)
    for case, result, where in results:
        if result.outcome not in PASSED:
            classes[failure_class(case, result)].append((case, result, where))
    print(f"\n{len(classes)} classes of failure:\n")
    for name, cases in sorted(classes.items(), key=lambda item: -len(item[1])):
        case, result, where = cases[0]
        commands = sorted({" ".join(c.argv[:2]) if c.argv[0] == "bench" else c.argv[0]
                           for c, _, _ in cases})
        print(f"- {name}: {len(cases)} cases ({', '.join(commands)}), e.g. [{case.kind}] "
              f"{case.what[:100]}\n"
              f"    {case.command()[:300]}\n    -> {result.detail[:200]}"
              + (f"\n    (scene file: {where}/scene.toml)" if case.scene_text and args.keep
                 else ""))


if __name__ == "__main__":
    main()

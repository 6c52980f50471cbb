"""Compare two folders written by scripts/behaviour_snapshot.sh (before and after a change).

Text and CSV files must be identical line for line; JSON documents are compared value by
value at every path present in both, so a refactoring may add fields or rename the ones listed
in RENAMED, but every number it kept must be bit-identical. Prints each difference and exits 1
if there is one.
    python3 scripts/compare_snapshots.py BEFORE AFTER
"""
import csv
import json
import pathlib
import re
import sys

# Document keys that a refactoring renamed on purpose: {file: [(old path prefix, new path
# prefix)]}, applied in order; a prefix mapped to None is a field that is no longer written.
RENAMED = {
    # Issue 10: `ctid feedback` writes the typed delayed_feedback_result document; it used to
    # write its own schema ("kind", "numerator", "diagnostics"). Its closed_loop α, β, γ were
    # those of the returned loop, which the document keeps (step 1's are in identification.step1).
    "feedback.json": [
        ("kind", None),
        ("coefficients", None),
        ("closed_loop.", None),
        ("diagnostics.delay_scan", "delay_scan"),
        ("diagnostics.step1.output_rms", "identification.step1_output_rms"),
        ("diagnostics.", "identification."),
        ("delay", "identification.loop.delay"),
        ("forward.numerator", "identification.loop.forward.numerator_ascending"),
        ("forward.denominator", "identification.loop.forward.denominator_ascending"),
        ("feedback.numerator", "identification.loop.feedback.numerator_ascending"),
        ("feedback.denominator", "identification.loop.feedback.denominator_ascending"),
    ],
}
# Lines of the text outputs that may differ in wording (not in numbers), as prefixes.
REWORDED_PREFIXES = ("termination:",)
# Wall-clock times in progress and summary lines are not results.
TIMING = re.compile(r"(\d+(\.\d+)? s on \d+ threads?|cases \(\d+ %\), \d+ s)")
# Wall-clock seconds of a batch record: a JSON key and a summary.csv column that are not results.
TIMING_KEY = "seconds"


def flatten(value, path=""):
    if isinstance(value, dict):
        for key, element in value.items():
            yield from flatten(element, f"{path}.{key}" if path else key)
    elif isinstance(value, list):
        for i, element in enumerate(value):
            yield from flatten(element, f"{path}[{i}]")
    else:
        yield path, value


def compare_json(before, after, name):
    old = dict(flatten(json.loads(before.read_text())))
    new = dict(flatten(json.loads(after.read_text())))
    renamed = {}
    for path, value in old.items():
        if path in new:  # both sides already in the same schema: nothing to rename
            renamed[path] = value
            continue
        for old_prefix, new_prefix in RENAMED.get(name, []):
            if path.startswith(old_prefix):
                path = None if new_prefix is None else new_prefix + path[len(old_prefix):]
                break
        if path is not None:
            renamed[path] = value
    old = renamed
    problems = []
    for path, value in old.items():
        if path.rsplit(".", 1)[-1] == TIMING_KEY:
            continue
        if path not in new:
            problems.append(f"{name}: {path} is gone")
        elif new[path] != value:
            problems.append(f"{name}: {path}: {value!r} -> {new[path]!r}")
    return problems


def without_timing_column(lines):
    """A CSV table's lines without its TIMING_KEY column (quoted fields kept as written)."""
    rows = list(csv.reader(lines))
    if not rows or TIMING_KEY not in rows[0]:
        return lines
    column = rows[0].index(TIMING_KEY)
    return [",".join(row[:column] + row[column + 1:]) for row in rows]


def compare_text(before, after, name):
    old = before.read_text().splitlines()
    new = after.read_text().splitlines()
    if before.suffix == ".csv":
        old, new = without_timing_column(old), without_timing_column(new)
    problems = []
    if len(old) != len(new):
        problems.append(f"{name}: {len(old)} lines -> {len(new)} lines")
    for i, (a, b) in enumerate(zip(old, new)):
        a, b = TIMING.sub("<time>", a), TIMING.sub("<time>", b)
        if a != b and not (a.startswith(REWORDED_PREFIXES) and b.startswith(REWORDED_PREFIXES)):
            problems.append(f"{name}:{i + 1}: {a!r} -> {b!r}")
    return problems


def main(before, after):
    before, after = pathlib.Path(before), pathlib.Path(after)
    problems = []
    for old in sorted(p for p in before.rglob("*") if p.is_file()):
        name = str(old.relative_to(before))
        new = after / name
        if not new.exists():
            problems.append(f"{name}: missing")
        elif old.suffix == ".json":
            problems += compare_json(old, new, name)
        elif old.suffix == ".png":
            continue
        else:
            problems += compare_text(old, new, name)
    for problem in problems:
        print(problem)
    print(f"compare_snapshots: {len(problems)} difference(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))

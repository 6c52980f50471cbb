"""Compare two folders written by scripts/behaviour_snapshot.sh (before and after a change).

Text and CSV files must be identical line for line; JSON documents are compared value by
value at every path present in both, so a refactoring may add fields or rename the ones listed
in RENAMED, but every number it kept must be bit-identical. Prints each difference and exits 1
if there is one.
    python3 scripts/compare_snapshots.py BEFORE AFTER
    python3 scripts/compare_snapshots.py --relative 1e-9 BEFORE AFTER
With --relative BOUND (issue 38's rule for changes that may alter rounding) numbers may differ:
JSON numbers and the numbers inside text and CSV lines are compared relatively, a number in a
list of numbers (a shape, a spectrum) relative to that list's largest magnitude, any other
relative to its own; the rest of each line must still be identical. It prints the largest
relative difference of each field (list indices written []) and exits 1 if one exceeds BOUND.
"""
import argparse
import csv
import json
import math
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
    # Decision 0055: counts of samples say so in their names (the options echoed by `ctid track`).
    "track.json": [
        ("options.identification.refined_iv.input_delay_fraction",
         "options.identification.refined_iv.input_delay_fraction"),
        ("options.identification.refined_iv.input_delay",
         "options.identification.refined_iv.input_delay_samples"),
        ("options.identification.refined_iv.record_input_delays",
         "options.identification.refined_iv.record_delay_samples"),
        ("options.identification.delay_scan", "options.identification.delay_scan_samples"),
    ],
    "track_mimo.json": [("options.refined_iv.input_delays", "options.refined_iv.input_delays_samples")],
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


INDEX = re.compile(r"\[\d+\]")
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def relative_difference(a, b, scale=0.0):
    if a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)):
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), scale)


def list_scales(value, path=""):
    """For every number inside a list of numbers, its list's largest magnitude."""
    if isinstance(value, dict):
        for key, element in value.items():
            yield from list_scales(element, f"{path}.{key}" if path else key)
    elif isinstance(value, list):
        numbers = [abs(e) for e in value
                   if isinstance(e, (int, float)) and not isinstance(e, bool) and math.isfinite(e)]
        scale = max(numbers, default=0.0)
        for i, element in enumerate(value):
            if isinstance(element, (dict, list)):
                yield from list_scales(element, f"{path}[{i}]")
            else:
                yield f"{path}[{i}]", scale


class Largest:
    """The largest relative difference of each field (indices written [])."""

    def __init__(self):
        self.fields = {}

    def add(self, name, path, difference):
        field = name + ": " + INDEX.sub("[]", path)
        if difference > self.fields.get(field, (-1.0, ""))[0]:
            self.fields[field] = (difference, path)


def is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def renamed_paths(old, new, name):
    """old's {path: value} under the names RENAMED gives them (paths new also has are kept)."""
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
    return renamed


def compare_json_relative(before, after, name, largest):
    old_document = json.loads(before.read_text())
    new = dict(flatten(json.loads(after.read_text())))
    old = renamed_paths(dict(flatten(old_document)), new, name)
    scales = renamed_paths(dict(list_scales(old_document)), new, name)
    problems = []
    for path, value in old.items():
        if path.rsplit(".", 1)[-1] == TIMING_KEY:
            continue
        if path not in new:
            problems.append(f"{name}: {path} is gone")
        elif is_number(value) and is_number(new[path]):
            largest.add(name, path, relative_difference(value, new[path], scales.get(path, 0.0)))
        elif new[path] != value:
            problems.append(f"{name}: {path}: {value!r} -> {new[path]!r}")
    return problems


def comparable_lines(before, after, name):
    """Both files' lines (a CSV without its timing column) and a problem if their counts differ."""
    old = before.read_text().splitlines()
    new = after.read_text().splitlines()
    if before.suffix == ".csv":
        old, new = without_timing_column(old), without_timing_column(new)
    problems = []
    if len(old) != len(new):
        problems.append(f"{name}: {len(old)} lines -> {len(new)} lines")
    return old, new, problems


def compare_text_relative(before, after, name, largest):
    old, new, problems = comparable_lines(before, after, name)
    for i, (a, b) in enumerate(zip(old, new)):
        a, b = TIMING.sub("<time>", a), TIMING.sub("<time>", b)
        if NUMBER.sub("#", a) != NUMBER.sub("#", b):
            problems.append(f"{name}:{i + 1}: {a!r} -> {b!r}")
            continue
        for x, y in zip(NUMBER.findall(a), NUMBER.findall(b)):
            largest.add(name, "lines", relative_difference(float(x), float(y)))
    return problems


def compare_json(before, after, name):
    new = dict(flatten(json.loads(after.read_text())))
    old = renamed_paths(dict(flatten(json.loads(before.read_text()))), new, name)
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
    old, new, problems = comparable_lines(before, after, name)
    for i, (a, b) in enumerate(zip(old, new)):
        a, b = TIMING.sub("<time>", a), TIMING.sub("<time>", b)
        if a != b and not (a.startswith(REWORDED_PREFIXES) and b.startswith(REWORDED_PREFIXES)):
            problems.append(f"{name}:{i + 1}: {a!r} -> {b!r}")
    return problems


def main(before, after, bound=None):
    before, after = pathlib.Path(before), pathlib.Path(after)
    problems = []
    largest = Largest()
    for old in sorted(p for p in before.rglob("*") if p.is_file()):
        name = str(old.relative_to(before))
        new = after / name
        if not new.exists():
            problems.append(f"{name}: missing")
        elif old.suffix == ".png":
            continue
        elif bound is not None:
            compare = compare_json_relative if old.suffix == ".json" else compare_text_relative
            problems += compare(old, new, name, largest)
        elif old.suffix == ".json":
            problems += compare_json(old, new, name)
        else:
            problems += compare_text(old, new, name)
    for problem in problems:
        print(problem)
    if bound is None:
        print(f"compare_snapshots: {len(problems)} difference(s)")
        return 1 if problems else 0
    over = 0
    for field, (difference, path) in sorted(largest.fields.items()):
        if difference > 0.0:
            print(f"{difference:.1e}  {field}  (at {path})")
        over += difference > bound
    print(f"compare_snapshots: {len(problems)} difference(s) other than in numbers; {over} "
          f"field(s) differ by more than {bound:g} relative; largest "
          f"{max((d for d, _ in largest.fields.values()), default=0.0):.1e}")
    return 1 if problems or over else 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("before")
    parser.add_argument("after")
    parser.add_argument("--relative", type=float, metavar="BOUND",
                        help="numbers may differ by up to BOUND relative (issue 38)")
    arguments = parser.parse_args()
    sys.exit(main(arguments.before, arguments.after, arguments.relative))

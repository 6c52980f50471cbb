"""Runs examples/feedback_delay_section4.cc and checks the validation MSEs it prints against the
two tables of docs/feedback-delay-section4.md (our MSE and E[MSE], quoted to three significant
digits):
the test fails when the example's numbers and the document drift apart.

usage: check_feedback_delay_section4.py EXAMPLE_EXECUTABLE DOCUMENT.md
"""
import re
import subprocess
import sys

NUMBER = r"([0-9.]+e[+-]?[0-9]+)"


def main():
    executable, document = sys.argv[1], sys.argv[2]
    printed_text = subprocess.run([executable], capture_output=True, text=True,
                                  check=True).stdout
    printed = re.findall(r"MSE_[FH] = " + NUMBER + r" \(E = " + NUMBER + r"\)", printed_text)
    quoted = []
    with open(document, encoding="utf-8") as doc:
        for line in doc:
            m = re.match(r"\| (min J|GCD), (?:F\u0302|\u0124) \|.*\| " + NUMBER + r" \(" + NUMBER +
                         r"\) \| [^|]+ \|\s*$", line)
            if m:
                quoted.append((m.group(2), m.group(3)))
    if len(printed) != 8 or len(quoted) != 8:
        sys.exit(f"expected 8 MSE pairs in each, got {len(printed)} printed and {len(quoted)} "
                 f"quoted\n--- printed ---\n{printed_text}")
    bad = []
    for index, ((mse, expected), (doc_mse, doc_expected)) in enumerate(zip(printed, quoted)):
        for got, want, what in ((mse, doc_mse, "MSE"), (expected, doc_expected, "E[MSE]")):
            # The document rounds to three significant digits (half a unit of the last one is
            # at most 0.5 % of the value); the example prints four (0.05 % more).
            if abs(float(got) - float(want)) > 0.0055 * abs(float(want)):
                bad.append(f"row {index + 1} {what}: the example prints {got}, the document "
                           f"quotes {want}")
    if bad:
        sys.exit("\n".join(bad))
    print(f"{len(printed)} MSE pairs match {document}")


if __name__ == "__main__":
    main()

"""Every Python example in docs/ that prints, followed by a plain block holding its printout, is
what this build prints: the python block is run in a scratch folder and its output compared
with the block after it, line by line (trailing blanks aside), so a change that moves a number or a repr fails here.
(README.md's example is checked the same way in test_readme.py; shell transcripts in
test_doc_transcripts.py.)"""

import glob
import os
import subprocess
import sys

import pytest

import ctid
import transcripts

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def printing_examples():
    """[(document, block number, code, printout)] of docs/**/*.md."""
    found = []
    for document in sorted(glob.glob("docs/**/*.md", root_dir=ROOT, recursive=True)):
        with open(os.path.join(ROOT, document)) as f:
            blocks = transcripts.fenced_blocks(f.read())
        for k, (language, code) in enumerate(blocks[:-1]):
            after_language, printout = blocks[k + 1]
            if language == "python" and "print(" in code and after_language == "":
                found.append((document, k, code, printout))
    return found


def test_the_python_reference_has_a_printing_example():
    assert "docs/python.md" in {document for document, *_ in printing_examples()}


@pytest.mark.parametrize("document, number, code, printout", printing_examples(),
                         ids=[f"{d}-{k}" for d, k, *_ in printing_examples()])
def test_printout_is_what_this_build_prints(document, number, code, printout, tmp_path):
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300,
                         env={**os.environ, "MPLBACKEND": "Agg",
                              "PYTHONPATH": os.path.dirname(os.path.dirname(ctid.__file__))})
    assert run.returncode == 0, f"{document}, block {number}: {run.stderr}"
    def lines(text):  # trailing blanks (print's separators) are not shown in Markdown
        return [line.rstrip() for line in text.rstrip("\n").split("\n")]

    assert lines(run.stdout) == lines(printout), f"{document}, block {number} prints:\n{run.stdout}"

"""The README's Python transcript is what this build prints: the python block run, its printout
compared with the block that follows it. (Its command-line transcript is checked with every
other document's in test_doc_transcripts.py.) A change that moves a number fails here."""

import os
import subprocess
import sys

import ctid
import transcripts

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def readme_blocks():
    with open(os.path.join(ROOT, "README.md")) as f:
        return transcripts.fenced_blocks(f.read())


def test_python_transcript(tmp_path):
    blocks = readme_blocks()
    index = next(i for i, (lang, b) in enumerate(blocks) if lang == "python")
    code, printed = blocks[index][1], blocks[index + 1][1]
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300,
                         env={**os.environ, "MPLBACKEND": "Agg",
                              "PYTHONPATH": os.path.dirname(os.path.dirname(ctid.__file__))})
    assert run.returncode == 0, run.stderr
    assert run.stdout.rstrip("\n").split("\n") == printed.rstrip("\n").split("\n"), run.stdout

"""The README's transcripts are what this build prints: the command-line block (every `$ ctid`
command run in a scratch folder, its output compared line by line with the README's, a line
`...` standing for any number of lines) and the Python block (run, its printout compared with
the block that follows it). A change that moves a number fails here, naming the line."""

import os
import re
import shlex
import subprocess
import sys

import pytest

import ctid

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("CTID_BUILD_DIR", os.path.join(ROOT, "build"))
CTID = os.path.join(BUILD, "apps", "ctid", "ctid")


def readme_blocks():
    with open(os.path.join(ROOT, "README.md")) as f:
        text = f.read()
    return re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S)


def matches(expected, actual):
    """Line-by-line equality, `...` in `expected` matching any run of lines (also none)."""
    if not expected:
        return not actual
    if expected[0] == "...":
        return any(matches(expected[1:], actual[k:]) for k in range(len(actual) + 1))
    return bool(actual) and expected[0] == actual[0] and matches(expected[1:], actual[1:])


def transcript(block):
    """[(command, expected output lines)] of a block of `$ ` lines and their output."""
    steps = []
    lines = block.rstrip("\n").split("\n")
    k = 0
    while k < len(lines):
        assert lines[k].startswith("$ "), lines[k]
        command = lines[k][2:]
        while command.endswith("\\"):
            k += 1
            command = command[:-1] + " " + lines[k].strip()
        k += 1
        output = []
        while k < len(lines) and not lines[k].startswith("$ "):
            output.append(lines[k])
            k += 1
        steps.append((command, output))
    return steps


@pytest.mark.skipif(not os.path.exists(CTID), reason="ctid executable not built")
def test_command_line_transcript(tmp_path):
    blocks = [b for lang, b in readme_blocks() if b.startswith("$ ctid ")]
    assert blocks, "README.md has a command-line transcript"
    os.symlink(os.path.join(ROOT, "examples"), tmp_path / "examples")
    for command, expected in transcript(blocks[0]):
        argv = shlex.split(command)
        assert argv[0] == "ctid"
        run = subprocess.run([CTID] + argv[1:], cwd=tmp_path, capture_output=True, text=True,
                             timeout=300)
        assert run.returncode == 0, run.stderr
        actual = run.stdout.rstrip("\n").split("\n")
        assert matches(expected, actual), (
            f"README.md: the output of `{command}` differs from what this build prints:\n"
            + "\n".join(actual))


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

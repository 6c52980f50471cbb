"""Shell transcripts in the documentation, run and compared with what this build prints.

A transcript is a fenced block whose first line starts with ``$ ctid ``: ``$ `` lines are
commands (a trailing backslash continues one, ``# ...`` after a command is a comment), the
lines up to the next command its expected standard output. In the expected output a line
``...`` (indented or not) stands for any number of lines (also none), ``...`` inside a line for any text, and
``<name>`` for any text (a placeholder such as ``<N>``). ``$ echo $?`` checks the exit status of
the command before it; any other command must exit 0."""

import os
import re
import shlex
import subprocess


def fenced_blocks(text):
    """[(language, body)] of the ``` blocks of a Markdown text."""
    return re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S)


def transcript_blocks(text):
    return [body for _, body in fenced_blocks(text) if body.startswith("$ ctid ")]


def steps(block):
    """[(command, expected output lines)] of a transcript block."""
    result = []
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
        result.append((command, output))
    return result


def _line_pattern(expected):
    parts = re.split(r"(\.\.\.|<[^<>\s][^<>]*>)", expected)
    return "".join(".*" if p == "..." or (p.startswith("<") and p.endswith(">")) else re.escape(p)
                   for p in parts)


def matches(expected, actual):
    """Line by line, with the wildcards of the module's docstring."""
    if not expected:
        return not actual
    if expected[0].strip() == "...":
        return any(matches(expected[1:], actual[k:]) for k in range(len(actual) + 1))
    return (bool(actual) and re.fullmatch(_line_pattern(expected[0]), actual[0]) is not None
            and matches(expected[1:], actual[1:]))


def run_transcript(block, ctid_executable, folder, where):
    """Runs every command of `block` in `folder`; AssertionError naming `where` and the command
    on the first difference."""
    commands = steps(block)
    status = None
    for k, (command, expected) in enumerate(commands):
        argv = shlex.split(command, comments=True)
        if argv == ["echo", "$?"]:
            assert expected == [str(status)], (
                f"{where}: `{command}` shows {expected}; the command before it exited {status}")
            continue
        assert argv[0] == "ctid", f"{where}: only ctid commands run here: {command}"
        run = subprocess.run([ctid_executable] + argv[1:], cwd=folder, capture_output=True,
                             text=True, timeout=600)
        status = run.returncode
        status_shown = k + 1 < len(commands) and commands[k + 1][0] == "echo $?"
        if not status_shown:
            assert status == 0, f"{where}: `{command}` exited {status}: {run.stderr}"
        actual = run.stdout.rstrip("\n").split("\n") if run.stdout else []
        assert matches(expected, actual), (
            f"{where}: the output of `{command}` differs from what this build prints:\n"
            + run.stdout)


def link_repository_folders(root, folder):
    """examples/ and data/ of the repository, visible from `folder` as in a checkout."""
    for name in ("examples", "data"):
        os.symlink(os.path.join(root, name), os.path.join(folder, name))

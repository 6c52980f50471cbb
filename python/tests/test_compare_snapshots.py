"""scripts/compare_snapshots.py: exact by default; with --relative BOUND (issue 38's rounding
rule) numbers may move within BOUND, a number in a list of numbers relative to that list's
largest magnitude, and anything else that differs still fails."""

import json
import pathlib
import subprocess
import sys

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "scripts" / "compare_snapshots.py"


def _folders(tmp_path, before, after, text=("f = 1.5 Hz", "f = 1.5 Hz")):
    folders = []
    for name, document, line in (("before", before, text[0]), ("after", after, text[1])):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "r.json").write_text(json.dumps(document))
        (folder / "r.txt").write_text(line + "\n")
        folders.append(str(folder))
    return folders


def _compare(*arguments):
    done = subprocess.run([sys.executable, str(SCRIPT), *arguments], capture_output=True,
                          text=True)
    return done.returncode, done.stdout


def test_relative_bound_on_numbers_and_list_scale(tmp_path):
    before = {"mode": {"f": 2.0, "shape": [1.0, 1e-6]}, "kind": "stable"}
    # f moves by 5e-10 relative; the shape's small entry by 5e-10 of the list's largest (1.0),
    # although by 5e-4 of itself.
    after = {"mode": {"f": 2.0 + 1e-9, "shape": [1.0, 1e-6 + 5e-10]}, "kind": "stable"}
    folders = _folders(tmp_path, before, after, ("f = 1.5 Hz", "f = 1.5000000001 Hz"))
    assert _compare(*folders)[0] == 1  # exact by default
    code, out = _compare("--relative", "1e-9", *folders)
    assert code == 0, out
    assert "5.0e-10  r.json: mode.f" in out
    assert "5.0e-10  r.json: mode.shape[]" in out
    assert _compare("--relative", "1e-10", *folders)[0] == 1


def test_relative_mode_still_fails_on_words_and_missing_fields(tmp_path):
    before = {"mode": {"f": 2.0}, "kind": "stable"}
    folders = _folders(tmp_path, before, {"mode": {"f": 2.0}, "kind": "new"})
    code, out = _compare("--relative", "1e-9", *folders)
    assert code == 1 and "kind: 'stable' -> 'new'" in out
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "r.json").write_text(json.dumps({"kind": "stable"}))
    (tmp_path / "other" / "r.txt").write_text("f = 1.5 kHz\n")
    code, out = _compare("--relative", "1e-9", folders[0], str(tmp_path / "other"))
    assert code == 1 and "mode.f is gone" in out and "r.txt:1" in out

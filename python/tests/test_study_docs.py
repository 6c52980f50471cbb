"""docs/study.md quotes the committed study results exactly, and the committed results are what
the current code produces (scripts/check_study_docs.py: the reduced studies rerun, the
paper-size studies' sample runs replayed). The checker itself is tested to fail, naming the
line or row and both values, on a doc number or a CSV value that was altered."""

import csv
import importlib.util
import pathlib
import re
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SPEC = importlib.util.spec_from_file_location("check_study_docs",
                                              ROOT / "scripts" / "check_study_docs.py")
check = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(check)


def test_doc_numbers_match_the_committed_results():
    errors = check.check_docs()
    assert not errors, "\n".join(errors)


def test_committed_results_match_the_current_code(cli):
    errors = check.check_code(cli)
    assert not errors, "\n".join(errors)


def altered(text):
    """A number text with its last digit changed (9 -> 8, else +1)."""
    last = text[-1]
    return text[:-1] + ("8" if last == "9" else str(int(last) + 1))


def alter_doc(tmp_path, line_pattern, number_pattern):
    """A copy of docs/study.md with the first number matching `number_pattern` on the first
    line matching `line_pattern` altered; returns (copy, line number, old, new)."""
    lines = check.DOC.read_text().split("\n")
    index = next(i for i, line in enumerate(lines) if re.search(line_pattern, line))
    match = re.search(number_pattern, lines[index])
    old = match.group(1)
    new = altered(old)
    lines[index] = lines[index][:match.start(1)] + new + lines[index][match.end(1):]
    copy = tmp_path / "study.md"
    copy.write_text("\n".join(lines))
    return copy, index + 1, old, new


def test_an_altered_table_number_is_reported_with_its_line(tmp_path):
    doc, line, old, new = alter_doc(tmp_path, r"^\| additive \| b20 \|",
                                    r"\| \**([−\d.]+)\** \|$")
    errors = check.check_docs(doc)
    assert len(errors) == 1, errors
    assert f"docs/study.md:{line}:" in errors[0]
    assert repr(new) in errors[0] and errors[0].endswith(f"gives {old}")


def test_an_altered_prose_number_is_reported_with_its_line(tmp_path):
    doc, line, old, new = alter_doc(tmp_path, r"\d+/\d+ SRIVC", r"(\d+)/\d+ SRIVC")
    errors = check.check_docs(doc)
    assert len(errors) == 1, errors
    assert f"docs/study.md:{line}:" in errors[0]
    assert repr(new) in errors[0] and errors[0].endswith(f"gives {old}")


def rewrite_csv(path, change):
    """Apply change(rows) to a CSV file in place; returns the rows."""
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        rows, fields = list(reader), reader.fieldnames
    change(rows)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=fields, lineterminator="\n")
        writer.writeheader()
        writer.writerows(rows)
    return rows


def test_an_altered_converged_count_is_reported_in_the_doc_check(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(check.RESULTS, results)

    def one_fewer_converged(rows):
        for r in rows:
            if r["estimator"] == "srivc" and r["size_index"] == "0":
                r["converged_runs"] = str(int(r["converged_runs"]) - 1)

    rewrite_csv(results / "open-loop-full" / "mse.csv", one_fewer_converged)
    before = check.Study(check.RESULTS / "open-loop-full").converged("srivc")
    errors = check.check_docs(results=results)
    assert len(errors) == 1, errors
    assert f"'{before}' in" in errors[0] and errors[0].endswith(f"gives {before - 1}")


def test_an_mse_change_beyond_the_tolerance_is_reported_with_its_row(tmp_path):
    committed = check.read_csv(check.RESULTS / "open-loop" / "mse.csv")
    current = [dict(r) for r in committed]
    row = current[len(current) // 2]
    tolerance = check.mse_tolerance("mse", row)
    row["mse"] = repr(float(row["mse"]) + 3 * tolerance)
    current[0]["mse"] = repr(float(current[0]["mse"]) + 0.3 * check.mse_tolerance("mse",
                                                                                  current[0]))
    errors = check.compare_rows("mse.csv", committed, current, check.MSE_KEYS,
                                check.mse_tolerance)
    assert len(errors) == 1, errors
    key = (row["estimator"], row["size_index"], row["parameter"])
    assert str(key) in errors[0] and row["mse"] in errors[0]
    assert committed[len(current) // 2]["mse"] in errors[0]


def test_an_altered_sample_estimate_is_reported_by_the_replay(cli, tmp_path):
    results = tmp_path / "results" / "open-loop-full"
    results.mkdir(parents=True)
    shutil.copy(check.RESULTS / "open-loop-full" / "runs-sample.csv", results)

    def keep_run_0_at_size_0_and_alter_b20(rows):
        rows[:] = [r for r in rows if r["size_index"] == "0" and r["run_index"] == "0"]
        rows[0]["b20"] = repr(float(rows[0]["b20"]) * (1 + 10 * check.RTOL))

    rows = rewrite_csv(results / "runs-sample.csv", keep_run_0_at_size_0_and_alter_b20)
    errors = check.replay_sample(cli, "open-loop-full", results.parent, tmp_path)
    assert len(errors) == 1, errors
    assert "b20" in errors[0] and rows[0]["b20"] in errors[0]
    assert str((rows[0]["estimator"], "0", "0")) in errors[0]


@pytest.mark.parametrize("bad", ["--write --use-output nonsense=/tmp"])
def test_unknown_study_names_are_refused(bad):
    with pytest.raises(SystemExit):
        check.main(bad.split())


def test_write_touches_only_the_result_files(cli, tmp_path):
    outputs, results = {}, tmp_path / "results"
    for name in check.STUDIES:  # study outputs made of the committed files, no reruns
        outputs[name] = tmp_path / "out" / name
        outputs[name].mkdir(parents=True)
        for file in ("mse.csv", "trends.csv"):
            shutil.copy(check.RESULTS / name / file, outputs[name])
        if (check.RESULTS / name / "runs-sample.csv").exists():
            shutil.copy(check.RESULTS / name / "runs-sample.csv", outputs[name] / "runs.csv")
        (results / name).mkdir(parents=True)
        (results / name / "notes.txt").write_text("kept")
    written = check.write_results(cli, outputs=outputs, results=results)
    assert written == list(check.STUDIES)
    files = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    expected = {"results/" + n + "/" + f for n in check.STUDIES
                for f in ("mse.csv", "trends.csv", "mse.png", "notes.txt")}
    expected |= {f"results/{n}/runs-sample.csv" for n in check.STUDIES if check.STUDIES[n][2]}
    expected |= {str(p.relative_to(tmp_path)) for p in (tmp_path / "out").rglob("*")
                 if p.is_file()}
    assert set(files) == expected
    for name in check.STUDIES:
        assert (results / name / "notes.txt").read_text() == "kept"
        for file in ("mse.csv", "trends.csv", "runs-sample.csv"):
            if (check.RESULTS / name / file).exists():
                assert (results / name / file).read_bytes() == \
                    (check.RESULTS / name / file).read_bytes()


def test_a_sample_missing_a_run_is_reported(tmp_path):
    results = tmp_path / "results"
    shutil.copytree(check.RESULTS, results)
    rows = rewrite_csv(results / "closed-loop-full" / "runs-sample.csv", lambda rows: rows.pop())
    errors = check.check_docs(results=results)
    assert len(errors) == 1, errors
    assert errors[0].startswith("closed-loop-full/runs-sample.csv:")
    assert f"{len(rows)} rows" in errors[0]

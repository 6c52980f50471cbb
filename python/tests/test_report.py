"""ctid report (python/ctid/report.py behind apps/ctid/report_command.cc): the page made from
what `ctid fit`, `ctid validate` and `ctid oma` write is rendered by headless Chromium, and the
rendered page is checked: every image decoded (naturalWidth > 0), the verdict and the tables'
numbers present, the screenshot not blank. Bad input is one line and exit status 2.

Chromium (Debian package `chromium`) is needed; without it the rendering tests are skipped,
except under CI=true, where its absence fails them."""

import json
import os
import pathlib
import re
import shutil
import subprocess

import numpy as np
import pytest

import ctid
from ctid import report

ROOT = pathlib.Path(__file__).resolve().parents[2]
DRYER = ROOT / "data" / "daisy_dryer_ljung" / "dryer.csv"
DRYER_COLUMNS = ["--time-column", "t_s_assumed_0.08", "--input-column", "u_heater_voltage",
                 "--output-column", "y_outlet_temperature", "--detrend", "mean"]

# Appended to a copy of the page for the test only (the report holds no script): once the page
# has loaded, a paragraph says how many of its images decoded.
MARKER = """<script>
window.addEventListener("load", () => {
  const images = Array.from(document.images);
  const decoded = images.filter((i) => i.complete && i.naturalWidth > 0).length;
  const p = document.createElement("p");
  p.id = "ctid-test-marker";
  p.textContent = "images decoded " + decoded + " of " + images.length;
  document.body.appendChild(p);
});
</script>"""


def _run(cli, *args, cwd=None):
    return subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True, cwd=cwd,
                          timeout=120)


@pytest.fixture(scope="module")
def pages(cli, tmp_path_factory):
    """fit.json, validation.json and oma.json as the command line writes them, and the two
    pages ctid report makes of them."""
    folder = tmp_path_factory.mktemp("report")
    fit = folder / "fit.json"
    done = _run(cli, "fit", DRYER, *DRYER_COLUMNS, "--rows", "0:500", "--poles", "2",
                "--zeros", "0", "--input-delay-samples", "2", "-o", fit, "-q")
    assert done.returncode == 0, done.stderr
    validation = folder / "validation.json"
    done = _run(cli, "validate", fit, DRYER, *DRYER_COLUMNS, "--rows", "500:1000", "-o",
                validation, "-q")
    assert done.returncode == 0, done.stderr
    from test_oma import H, _record

    y, _ = _record(5, samples=6000)
    np.savetxt(folder / "chain.csv", y, delimiter=",", header="a,b,c", comments="")
    oma = folder / "oma.json"
    done = _run(cli, "oma", folder / "chain.csv", "--output-columns", "a,b,c", "-T", H,
                "--max-order", "12", "-o", oma, "-q")
    assert done.returncode == 0, done.stderr
    fit_page = folder / "fit.html"
    done = _run(cli, "report", fit, validation, "-o", fit_page)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(str(fit_page))
    oma_page = folder / "oma.html"
    done = _run(cli, "report", oma, "-o", oma_page, "--title", "Chain, output only")
    assert done.returncode == 0, done.stderr
    return {"folder": folder, "fit": fit, "validation": validation, "oma": oma,
            "fit_page": fit_page, "oma_page": oma_page}


def _chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        if shutil.which(name):
            return shutil.which(name)
    if os.environ.get("CI") == "true":
        pytest.fail("chromium is not installed (Debian package chromium); CI must have it")
    pytest.skip("chromium is not installed (Debian package chromium)")


def _browser(*args):
    command = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu",
               "--disable-dev-shm-usage", "--hide-scrollbars", "--virtual-time-budget=10000",
               *args]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def _rendered(page):
    """The DOM Chromium rendered from a copy of ``page`` with MARKER added, as text."""
    probe = page.with_name(page.stem + ".probe.html")
    probe.write_text(page.read_text(encoding="utf-8").replace("</body>", MARKER + "</body>"),
                     encoding="utf-8")
    return _browser("--dump-dom", probe.as_uri())


def _text(dom):
    """The DOM's text, tags and entities aside, spaces collapsed."""
    import html

    body = re.sub(r"<(script|style)[^>]*>.*?</\1>", " ", dom, flags=re.S)
    return " ".join(html.unescape(re.sub(r"<[^>]+>", " ", body)).split())


def test_the_fit_page_renders_with_every_figure_and_the_verdict(pages):
    dom = _rendered(pages["fit_page"])
    marker = re.search(r'id="ctid-test-marker">images decoded (\d+) of (\d+)<', dom)
    assert marker, "the page did not finish loading in Chromium"
    decoded, total = int(marker.group(1)), int(marker.group(2))
    assert total == 2 and decoded == total  # Bode diagram, residual correlations
    text = _text(dom)
    fit = json.loads(pages["fit"].read_text())
    validation = json.loads(pages["validation"].read_text())
    assert fit["verdict"]["usable"]
    assert "Fit: The fitted model is usable" in text
    assert f"fits the estimation data to {fit['fit_percent']:.1f} %" in text
    assert (f"reproduces the measured output with a fit of "
            f"{validation['fit_percent']:.1f} %") in text
    white = validation["max_residual_autocorrelation"] <= validation["whiteness_bound"]
    assert ("The residuals are white" if white else "The residuals are NOT white") in text
    assert "99 % bound" in text and "95 % confidence band" in text
    # The parameter table: every parameter with its value and standard error.
    for name, value, error in zip(fit["parameter_names"], fit["parameters"],
                                  fit["standard_errors"]):
        assert f"{name} {report._number(value)} {report._number(error, 2)}" in text
    # How it was made: the data file and preprocessing the documents record, the page's command.
    offset = report._number(fit["data"]["preprocessing"]["output_offset"])
    assert str(DRYER) in text and "rows 0:500; detrend mean" in text and offset in text
    assert f"ctid report {pages['fit']} {pages['validation']} --output" in text


def test_the_fit_page_screenshot_is_not_blank(pages):
    import matplotlib.image

    shot = pages["folder"] / "fit.png"
    _browser(f"--screenshot={shot}", "--window-size=1000,1400", pages["fit_page"].as_uri())
    pixels = matplotlib.image.imread(shot)[..., :3]
    assert pixels.shape[:2] == (1400, 1000)
    ink = np.mean(pixels, axis=2) < 0.9  # anything darker than the near-white background
    assert ink.mean() > 0.03, f"only {100 * ink.mean():.2f} % of the screenshot is drawn"
    # Not one flat colour either: the figures and the text vary.
    assert pixels.std() > 0.05


def test_a_fit_that_failed_its_verdict_says_why_and_what_to_try(pages, tmp_path):
    document = json.loads(pages["fit"].read_text())
    document["verdict"] = {"usable": False, "reasons": ["The poles are unstable."],
                           "advice": "fewer poles"}
    failed = tmp_path / "failed.json"
    failed.write_text(json.dumps(document))
    page = report.render([str(failed)])
    assert '<div class="verdict bad"><strong>Fit:</strong> The fitted model is NOT usable as ' \
        "it is: The poles are unstable. What to try: fewer poles</div>" in page


def test_the_oma_page_renders_its_modes_and_stabilisation_diagram(pages):
    """The diagram, and the modes' shapes and auto-MAC."""
    dom = _rendered(pages["oma_page"])
    marker = re.search(r'images decoded (\d+) of (\d+)', dom)
    assert marker and marker.group(1) == marker.group(2) == "3"
    text = _text(dom)
    oma = json.loads(pages["oma"].read_text())
    assert "Chain, output only" in text
    count = len(oma["modes"])
    assert count == 3
    assert f"found {count} modes in 3 channels" in text
    for mode in oma["modes"]:
        assert report._plus_minus(mode["frequency_hz"], mode["frequency_hz_std"]) in text


def test_an_unknown_document_type_is_one_clear_error(cli, pages, tmp_path):
    other = tmp_path / "frf.json"
    other.write_text('{"type": "frf", "version": 1}')
    done = _run(cli, "report", other, "-o", tmp_path / "x.html")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1
    assert done.stderr.startswith(f"ctid report: error: {other}: a 'frf' document is not one "
                                  "ctid report reads; it reads estimation_result")
    assert not (tmp_path / "x.html").exists()


@pytest.mark.parametrize("content, message", [
    (None, "no such file"),
    ("not json", "not a JSON document"),
    ("[1, 2]", "expected a JSON object"),
])
def test_bad_input_is_one_line_and_exit_status_2(cli, tmp_path, content, message):
    path = tmp_path / "in.json"
    if content is not None:
        path.write_text(content)
    done = _run(cli, "report", path, "-o", tmp_path / "x.html")
    assert (done.returncode, done.stderr.count("\n")) == (2, 1), done.stderr
    assert message in done.stderr and "Traceback" not in done.stderr


def test_a_second_document_must_be_a_validation_report(cli, pages, tmp_path):
    done = _run(cli, "report", pages["fit"], pages["oma"], "-o", tmp_path / "x.html")
    assert done.returncode == 2
    assert "the second document must be a validation_report" in done.stderr


def test_an_existing_page_is_kept_without_force(cli, pages, tmp_path):
    page = tmp_path / "kept.html"
    page.write_text("mine")
    done = _run(cli, "report", pages["oma"], "-o", page)
    assert done.returncode == 2 and page.read_text() == "mine"
    done = _run(cli, "report", pages["oma"], "-o", page, "--force")
    assert done.returncode == 0 and page.read_text().startswith("<!DOCTYPE html>")


def test_the_module_runs_without_the_command_line(pages, tmp_path):
    """python3 -m ctid.report is the same page (its command named as the module)."""
    page = tmp_path / "direct.html"
    assert report.main([str(pages["oma"]), "-o", str(page)]) == 0
    text = page.read_text()
    assert "python3 -m ctid.report" in text and "<img src=\"data:image/png;base64," in text


def test_an_fdd_page_draws_the_spectrum_and_claims_no_model_orders(tmp_path):
    from test_oma import H, _record

    y, _ = _record(6, samples=4000)
    path = tmp_path / "fdd.json"
    ctid.write_result(path, ctid.oma(y, H, method=ctid.OmaMethod.fdd))
    page = report.render([str(path)])
    assert page.count('<img src="data:image/png;base64,') == 3  # spectrum, shapes, MAC
    assert "picked on it" in page and "Hankel block rows" not in page


def test_a_rivc_fit_page_shows_its_noise_model_and_the_prediction(cli, tmp_path):
    fit = tmp_path / "rivc.json"
    done = _run(cli, "fit", DRYER, *DRYER_COLUMNS, "--rows", "0:500",
                "--poles", "2", "--zeros", "1", "--input-delay-samples", "2", "--noise-model",
                "2,1", "-o", fit, "-q")
    assert done.returncode == 0, done.stderr
    validation = tmp_path / "validation.json"
    done = _run(cli, "validate", fit, DRYER, *DRYER_COLUMNS, "--rows", "500:1000",
                "--horizon", "1", "-o", validation, "-q")
    assert done.returncode == 0, done.stderr
    page = report.render([str(fit), str(validation)])
    document = json.loads(fit.read_text())
    assert "<h3>Noise model: ARMA(2, 1), D(q⁻¹) v = C(q⁻¹) e</h3>" in page
    assert ">d1<" in page and ">c1<" in page and "innovation variance" in page
    assert document["estimator"] == "rivc"
    assert "1-step-ahead prediction fit (noise model)" in page


def test_a_polished_fit_page_shows_the_polish_beside_the_iv_estimate(cli, tmp_path):
    fit = tmp_path / "polished.json"
    done = _run(cli, "fit", DRYER, *DRYER_COLUMNS, "--rows", "0:500", "--poles", "2",
                "--zeros", "1", "--input-delay-samples", "2", "--dc-gain", "0.9",
                "-o", fit, "-q")
    assert done.returncode == 0, done.stderr
    document = json.loads(fit.read_text())
    page = report.render([str(fit)])
    assert "<h3>Output-error polish</h3>" in page
    assert "theta1.b0 (held)" in page and "tau [s]" in page
    assert document["polish"]["parameters"][2] == 0.9
    assert document["polish"]["cost"] <= document["polish"]["start_cost"]

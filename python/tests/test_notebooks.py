"""The notebooks of examples/notebooks run from start to end (nbclient, Debian's
python3-nbclient and python3-ipykernel) in their own folder, and what they print is what the
same computation gives here."""

import os
import pathlib
import re

import ctid

ROOT = pathlib.Path(__file__).resolve().parents[2]
NOTEBOOKS = ROOT / "examples" / "notebooks"


def _execute(path, monkeypatch):
    import nbclient
    import nbformat

    notebook = nbformat.read(path, as_version=4)
    # The kernel inherits this process's environment: the same ctid package (PYTHONPATH), and
    # IPython's own inline figures (no MPLBACKEND).
    package = str(pathlib.Path(ctid.__file__).resolve().parents[1])
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(
        [package] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    monkeypatch.delenv("MPLBACKEND", raising=False)
    client = nbclient.NotebookClient(notebook, timeout=120, kernel_name="python3",
                                     resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    return notebook


def _printed(notebook):
    return "".join(output.get("text", "") for cell in notebook.cells
                   if cell.cell_type == "code" for output in cell.get("outputs", [])
                   if output.get("output_type") == "stream")


def test_the_dryer_notebook_fits_and_validates_as_ctid_does_here(monkeypatch):
    notebook = _execute(NOTEBOOKS / "dryer.ipynb", monkeypatch)
    printed = _printed(notebook)
    data = ctid.read_csv(str(ROOT / "data" / "daisy_dryer_ljung" / "dryer.csv"),
                         time="t_s_assumed_0.08", input="u_heater_voltage",
                         output="y_outlet_temperature")
    estimation = data.preprocess(end_row=500, detrend=ctid.Detrend.mean).data
    validation = data.preprocess(first_row=500, detrend=ctid.Detrend.mean).data
    fit = ctid.identify(estimation, ctid.ModelStructure.unfactored(2, 0),
                        ctid.IdentificationOptions(delay_scan_samples=ctid.DelayRange(min=0, max=10)))
    expected = ctid.validate_model(fit.estimate.model, validation).fit_percent
    found = re.search(r"validation fit from rest: ([0-9.]+) %", printed)
    assert found, printed
    assert found.group(1) == f"{expected:.3f}"
    assert expected > 80.0  # docs/examples/dryer.md: the detrended fit validates above 80 %
    assert f"input delay: {fit.estimate.input_delay_samples} samples; usable: True" in printed
    # The figure cell drew one image.
    images = [output for cell in notebook.cells for output in cell.get("outputs", [])
              if "image/png" in output.get("data", {})]
    assert len(images) == 1

"""`pip install .` (decision 0047): a fresh virtual environment made from /usr/bin/python3 with
the system site packages, the package installed offline with Debian's setuptools, and `import
ctid` from another folder with no PYTHONPATH gives the installed copy, which computes. The
build step reuses CTID_BUILD_DIR (or build/), so nothing is compiled when it is up to date."""

import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("CTID_BUILD_DIR", ROOT / "build"))


def test_pip_install_into_a_fresh_venv_imports_ctid_from_anywhere(tmp_path):
    if not (BUILD / "CMakeCache.txt").is_file():
        pytest.fail(f"{BUILD} is not a configured build tree (set CTID_BUILD_DIR)")
    venv = tmp_path / "env"
    env = {key: value for key, value in os.environ.items()
           if key not in ("PYTHONPATH", "PYTHONHOME", "PIP_INDEX_URL", "PIP_EXTRA_INDEX_URL")}
    env.update(CTID_BUILD_DIR=str(BUILD), PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", str(venv)],
                   check=True, env=env, timeout=120)
    install = subprocess.run(
        [str(venv / "bin" / "pip"), "install", "--no-build-isolation", "--no-index", "-q",
         str(ROOT)], capture_output=True, text=True, env=env, timeout=600)
    assert install.returncode == 0, install.stdout[-3000:] + install.stderr[-3000:]
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    probe = ("import ctid, numpy\n"
             "g = ctid.TransferFunction([4.0], [4.0, 0.8, 1.0])\n"
             "y = ctid.simulate(g, numpy.ones(200), 0.05)\n"
             "print(ctid.__file__)\n"
             "print(ctid._ctid.__file__)\n"
             "print(repr(float(y[-1])))\n")
    run = subprocess.run([str(venv / "bin" / "python"), "-c", probe], cwd=elsewhere,
                         capture_output=True, text=True, env=env, timeout=120)
    assert run.returncode == 0, run.stderr
    package, module, last = run.stdout.split("\n")[:3]
    site = venv / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}"
    assert pathlib.Path(package).is_relative_to(site / "site-packages")
    assert pathlib.Path(module).parent == pathlib.Path(package).parent
    # The step response of 4 / (s^2 + 0.8 s + 4) after 10 s is near its DC gain 1.
    assert abs(float(last) - 1.0) < 0.05
    # The installed package carries the pure-Python modules beside the compiled one.
    assert (pathlib.Path(package).parent / "report.py").is_file()
    listing = subprocess.run([str(venv / "bin" / "pip"), "show", "ctid"], capture_output=True,
                             text=True, env=env, timeout=60)
    assert "Name: ctid" in listing.stdout
    # The installed package is also the command line (decision 0052), with no ctid binary on
    # the PATH: python -m ctid simulate writes the record the binary would.
    model = elsewhere / "g.json"
    model.write_text('{"type": "transfer_function", "numerator_ascending": [4.0], '
                     '"denominator_ascending": [4.0, 0.8, 1.0], "input_delay": 0.0}')
    (elsewhere / "u.csv").write_text("t,u\n" + "".join(f"{k * 0.05!r},1\n" for k in range(200)))
    simulated = subprocess.run(
        [str(venv / "bin" / "python"), "-m", "ctid", "simulate", "-m", str(model), "-i",
         str(elsewhere / "u.csv"), "-o", str(elsewhere / "y.csv"), "-q"],
        cwd=elsewhere, capture_output=True, text=True, timeout=120,
        env=dict(env, PATH=str(venv / "bin")))
    assert simulated.returncode == 0, simulated.stderr
    last_row = (elsewhere / "y.csv").read_text().strip().split("\n")[-1].split(",")
    assert abs(float(last_row[-1]) - float(last)) < 1e-9

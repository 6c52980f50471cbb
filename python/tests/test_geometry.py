"""Mode shapes on a sensor geometry (ctid.geometry, decision 0063): the CSV files are read with
one clear error per fault, a node moves by the sum of its channels' real shape entries along
their directions, and the figure draws the deformed wireframe at the stated scale, in 2-D and
3-D, from Python and from python3 -m ctid.plot."""

import subprocess
import sys

import numpy as np
import pytest

import ctid
from ctid import geometry, plotting

H = 0.01


def _write(path, text):
    path.write_text(text)
    return path


def _result(seed=5):
    """Two resonances (5 and 12 Hz) seen by three channels a, b, c."""
    rng = np.random.default_rng(seed)
    x = np.zeros((12000, 2))
    for i, hz in enumerate((5.0, 12.0)):
        w = 2 * np.pi * hz
        r = np.exp(-0.02 * w * H)
        a1, a2 = 2 * r * np.cos(w * H * np.sqrt(1 - 0.02 ** 2)), -r * r
        e = rng.standard_normal(12500)
        s1 = s2 = 0.0
        for k in range(12500):
            s1, s2 = a1 * s1 + a2 * s2 + e[k], s1
            if k >= 500:
                x[k - 500, i] = s1
    y = np.column_stack([x[:, 0] + x[:, 1], 0.5 * x[:, 0] - x[:, 1], -0.8 * x[:, 0] + 0.6 * x[:, 1]])
    y += 0.3 * rng.standard_normal(y.shape)
    return ctid.oma(y, H, max_order=12, channel_names=["a", "b", "c"])


def test_a_2d_geometry_with_lines_and_the_deformed_wireframe(tmp_path):
    sensors = _write(tmp_path / "s.csv", "channel,x,y\na,0,0\nb,1,0\nc,2,0\n")
    lines = _write(tmp_path / "l.csv", "from,to\na,b\nb,c\n")
    g = geometry.read_geometry(sensors, lines)
    assert geometry.DRAWN_SHARE == 0.15  # docs/oma.md: "15 % of the structure's largest extent"
    assert g.dimension == 2 and g.lines == [(0, 1), (1, 2)]
    np.testing.assert_array_equal(g.directions[:, :2], [[0, 1]] * 3)  # along y by default
    result = _result()
    assert len(result.modes) == 2
    figure = plotting.oma_mode_shapes(result, geometry=g, filename=str(tmp_path / "f.png"))
    assert len(figure.axes) == 2
    for ax, mode in zip(figure.axes, result.modes):
        shape = np.array(mode.shape_real)  # largest entry 1 (decision 0030)
        # The deformed line a-b (the last two-point line of the panel, before b-c).
        deformed = [line for line in ax.get_lines() if len(line.get_xdata()) == 2][-2]
        scale = geometry.DRAWN_SHARE * 2.0 / np.abs(shape).max()
        np.testing.assert_allclose(deformed.get_ydata(), scale * shape[:2], rtol=1e-12)
        np.testing.assert_allclose(deformed.get_xdata(), [0.0, 1.0])
    assert (tmp_path / "f.png").stat().st_size > 0


def test_a_triaxial_node_moves_by_its_three_channels():
    g = geometry.Geometry(["x", "y", "z", "w"],
                          [[1, 2, 3], [1, 2, 3], [1, 2, 3], [0, 0, 0]],
                          [[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 0, 1]], 3)
    assert len(g.nodes) == 2 and g.node_of == [0, 0, 0, 1]
    shape = np.array([0.2 + 1j, -0.5, 1.0, 0.3 - 0.1j])
    moved = geometry.node_displacements(g, ["w", "x", "y", "z"], shape[[3, 0, 1, 2]])
    np.testing.assert_allclose(moved, [[0.2, -0.5, 1.0], [0.0, 0.0, 0.3]])
    with pytest.raises(ValueError, match="the geometry's channel 'x' is not one of"):
        geometry.node_displacements(g, ["w"], shape[:1])


def test_a_3d_geometry_draws_3d_panels(tmp_path):
    sensors = _write(tmp_path / "s.csv",
                     "channel,x,y,z,dx,dy,dz\na,0,0,0,0,0,2\nb,0,0,1,1,0,0\nc,0,0,2,0,1,0\n")
    g = geometry.read_geometry(sensors)
    np.testing.assert_allclose(g.directions[0], [0, 0, 1])  # normalised
    figure = plotting.oma_mode_shapes(_result(), geometry=str(sensors))
    assert all(ax.name == "3d" for ax in figure.axes)


@pytest.mark.parametrize("text, lines, message", [
    ("channel,x\na,0\n", None, "needs the columns channel, x, y; y missing"),
    ("channel,x,y\na,0,zero\n", None, ":2: column 'y' is 'zero'; it must be a number"),
    ("channel,x,y\na,0,0\na,1,0\n", None, ":3: channel 'a' is listed twice"),
    ("channel,x,y,dx,dy\na,0,0,0,0\n", None, "channel 'a' has direction 0"),
    ("channel,x,y,dx\na,0,0,1\n", None, "a direction needs the columns dx, dy; only dx given"),
    ("channel,x,y\n", None, "no rows under the header"),
    ("channel,x,y\na,0,0\n", "from,to\na,q\n", "column 'to' names 'q', which is not a channel"),
])
def test_a_bad_geometry_is_one_clear_error(tmp_path, text, lines, message):
    sensors = _write(tmp_path / "s.csv", text)
    joined = None if lines is None else _write(tmp_path / "l.csv", lines)
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        geometry.read_geometry(sensors, joined)


def test_python_m_ctid_plot_draws_shapes_on_a_geometry(tmp_path):
    document = tmp_path / "oma.json"
    ctid.write_result(document, _result())
    sensors = _write(tmp_path / "s.csv", "channel,x,y\na,0,0\nb,1,0\nc,2,0\n")
    lines = _write(tmp_path / "l.csv", "from,to\na,b\nb,c\n")
    command = [sys.executable, "-m", "ctid.plot", "oma_shapes", str(document)]
    done = subprocess.run([*command, str(tmp_path / "s.png"), "--geometry", str(sensors),
                           "--geometry-lines", str(lines)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "s.png").stat().st_size > 0
    bad = _write(tmp_path / "bad.csv", "channel,x,y\nq,0,0\n")
    refused = subprocess.run([*command, str(tmp_path / "b.png"), "--geometry", str(bad)],
                             capture_output=True, text=True)
    assert refused.returncode == 2
    assert refused.stderr.count("\n") == 1
    assert "the geometry's channel 'q' is not one of the analysis's channels" in refused.stderr

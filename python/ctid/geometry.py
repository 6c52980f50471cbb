"""Sensor geometry for output-only mode shapes (decision 0063): where each channel's sensor is
and which way it measures, read from a CSV file, and the shapes drawn on it.

    geometry = ctid.geometry.read_geometry("sensors.csv", lines="lines.csv")
    ctid.plotting.oma_mode_shapes(result, geometry=geometry, filename="shapes.png")
    ctid oma data.csv --geometry sensors.csv [--geometry-lines lines.csv] --plot DIR

The sensors file has a header and one row per channel: ``channel,x,y`` and optionally ``z``
(3-D) and the measuring direction ``dx,dy`` (and ``dz`` in 3-D; default: along y in 2-D, along
z in 3-D; normalised). Channels at the same position are one node, so a triaxial sensor is
three rows with one position. The lines file (``from,to``, channel names) joins the nodes of
two channels for the wireframe. A node moves by the sum over its channels of the real part of
the shape's entry (largest entry 1, decision 0030) times the channel's direction; the deformed
wireframe is drawn over the undeformed one at a scale making the largest node displacement a
fixed share of the structure's extent.
"""

from __future__ import annotations

import csv
import math
import os

import numpy as np

__all__ = ["Geometry", "read_geometry", "node_displacements"]

# The largest node displacement drawn, as a share of the structure's largest extent.
DRAWN_SHARE = 0.15


class Geometry:
    """Channels' positions and directions (n x 3 each; z 0 in 2-D), the dimension (2 or 3), the
    nodes (distinct positions, k x 3), each channel's node index, and lines as node pairs."""

    def __init__(self, channels, positions, directions, dimension, lines=()):
        self.channels = list(channels)
        self.positions = np.asarray(positions, dtype=float)
        self.directions = np.asarray(directions, dtype=float)
        self.dimension = int(dimension)
        keys = [tuple(p) for p in self.positions]
        unique = list(dict.fromkeys(keys))
        self.nodes = np.array(unique, dtype=float).reshape(-1, 3)
        self.node_of = [unique.index(k) for k in keys]
        self.lines = [(self.node_of[a], self.node_of[b]) for a, b in lines]


def _number(text, file, line, column):
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise ValueError(f"{file}:{line}: column '{column}' is {text!r}; it must be a number")
    if not math.isfinite(value):
        raise ValueError(f"{file}:{line}: column '{column}' is {text!r}; it must be finite")
    return value


def _rows(file, required):
    if not os.path.isfile(file):
        raise ValueError(f"{file}: no such file")
    with open(file, newline="", encoding="utf-8") as handle:
        reader = csv.DictReader(handle)
        header = [h.strip() for h in (reader.fieldnames or [])]
        missing = [c for c in required if c not in header]
        if missing:
            raise ValueError(f"{file}: needs the columns {', '.join(required)}; "
                             f"{', '.join(missing)} missing (header: {', '.join(header)})")
        reader.fieldnames = header
        rows = [(i + 2, {k: (v or "").strip() for k, v in row.items() if k is not None})
                for i, row in enumerate(reader)]
    if not rows:
        raise ValueError(f"{file}: no rows under the header")
    return rows, header


def read_geometry(sensors, lines=None):
    """The Geometry of a sensors CSV file (channel, x, y[, z][, dx, dy[, dz]]) and an optional
    lines CSV file (from, to: channel names). Raises ValueError naming the file, line and
    column of what is wrong."""
    sensors = os.fspath(sensors)
    rows, header = _rows(sensors, ("channel", "x", "y"))
    dimension = 3 if "z" in header else 2
    axes = ("x", "y", "z")[:dimension]
    direction_columns = tuple("d" + a for a in axes)
    given = [c for c in direction_columns if c in header]
    if given and len(given) != dimension:
        raise ValueError(f"{sensors}: a direction needs the columns {', '.join(direction_columns)}; "
                         f"only {', '.join(given)} given")
    channels, positions, directions = [], [], []
    for line, row in rows:
        name = row["channel"]
        if not name:
            raise ValueError(f"{sensors}:{line}: column 'channel' is empty")
        if name in channels:
            raise ValueError(f"{sensors}:{line}: channel '{name}' is listed twice")
        position = [_number(row[a], sensors, line, a) for a in axes] + [0.0] * (3 - dimension)
        if given:
            direction = [_number(row[c], sensors, line, c) for c in direction_columns]
        else:
            direction = [0.0, 1.0] if dimension == 2 else [0.0, 0.0, 1.0]
        norm = math.hypot(*direction)
        if norm == 0.0:
            raise ValueError(f"{sensors}:{line}: channel '{name}' has direction 0")
        channels.append(name)
        positions.append(position)
        directions.append([d / norm for d in direction] + [0.0] * (3 - dimension))
    pairs = []
    if lines is not None:
        lines = os.fspath(lines)
        for line, row in _rows(lines, ("from", "to"))[0]:
            for end in ("from", "to"):
                if row[end] not in channels:
                    raise ValueError(f"{lines}:{line}: column '{end}' names '{row[end]}', which "
                                     f"is not a channel of {sensors}")
            pairs.append((channels.index(row["from"]), channels.index(row["to"])))
    return Geometry(channels, positions, directions, dimension, pairs)


def node_displacements(geometry, channels, shape):
    """Each node's displacement (k x 3) for the complex `shape` over `channels`: the sum over
    the node's geometry channels of Re(shape entry) times the channel's direction. Every
    geometry channel must be one of `channels`; channels without a sensor are not drawn."""
    channels = list(channels)
    shape = np.asarray(shape)
    moved = np.zeros_like(geometry.nodes)
    for k, name in enumerate(geometry.channels):
        if name not in channels:
            raise ValueError(f"the geometry's channel '{name}' is not one of the analysis's "
                             f"channels ({', '.join(channels)})")
        moved[geometry.node_of[k]] += shape[channels.index(name)].real * geometry.directions[k]
    return moved


def draw_shapes(result, geometry, modes, title_of, figure):
    """One panel per mode of `result` in `figure`: the undeformed wireframe (grey, dashed) and
    the deformed one (the mode's colour), at the scale DRAWN_SHARE. Returns the axes."""
    extent = np.ptp(geometry.nodes, axis=0).max() if len(geometry.nodes) > 1 else 1.0
    extent = extent if extent > 0.0 else 1.0
    columns = 1 if len(modes) == 1 else 2
    rows = math.ceil(len(modes) / columns)
    axes = []
    for i, mode in enumerate(modes):
        options = {"projection": "3d"} if geometry.dimension == 3 else {}
        ax = figure.add_subplot(rows, columns, i + 1, **options)
        moved = node_displacements(geometry, result.channels, mode.shape)
        largest = np.abs(moved).max()
        scale = DRAWN_SHARE * extent / largest if largest > 0.0 else 0.0
        for nodes, style in ((geometry.nodes, dict(color="0.6", ls="--", lw=0.8)),
                             (geometry.nodes + scale * moved, dict(color=f"C{i % 10}", lw=1.5))):
            coordinates = [nodes[:, a] for a in range(geometry.dimension)]
            ax.plot(*coordinates, "o", ms=3, color=style["color"])
            for a, b in geometry.lines:
                ax.plot(*[[nodes[a, d], nodes[b, d]] for d in range(geometry.dimension)],
                        **style)
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        if geometry.dimension == 2:
            ax.set_aspect("equal", adjustable="datalim")
        else:
            ax.set_zlabel("z")
        ax.set_title(title_of(mode), fontsize=9)
        axes.append(ax)
    return axes

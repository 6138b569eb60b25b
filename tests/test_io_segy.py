"""SEG-Y cubes through segyio (issue 16 acceptance): ``gc.Volume.from_segy`` / ``gc.io.from_segy``.

A cube is written in the test with segyio: inline and crossline numbers in their header bytes, CDP_X
/ CDP_Y with a scalar of -100 (centimetres), a survey rotated by 25° (inline step 25 m, crossline
step 12.5 m), depth samples from 1000 m every 4 m, and a dome whose apex lies under one known trace.

What is checked:
- the dome's apex (the highest point of the extracted isosurface, and the nearest pixel of a
  top-down orthographic render) lies where that trace's CDP_X / CDP_Y headers say, at z = -(apex
  depth): the survey's rotation, origin and spacing come from the headers; the dome renders
  apex-up (depth positive down); implicit culling gives the unculled image;
- left-handed surveys (crossline step clockwise of the inline step), crossline-sorted files and an
  already open (memory-mapped) SegyFile give the same apex;
- a skewed survey is an InputError saying so.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import geocull as gc

segyio = pytest.importorskip("segyio")

NA, NB, NS = 21, 31, 60  # inlines, crosslines, samples
APEX = (12, 17)  # (inline index, crossline index) of the dome's apex
APEX_DEPTH = 1060.0


def trace_xy(a, b, rotation=25.0, handed=1.0, skew=0.0):
    """World (x, y) of inline index a, crossline index b: inline step 25 m along the rotation,
    crossline step 12.5 m perpendicular to it (counter-clockwise for handed=1; off by ``skew``)."""
    t = math.radians(rotation)
    tv = t + handed * math.pi / 2 + skew
    return (431_000.0 + a * 25.0 * math.cos(t) + b * 12.5 * math.cos(tv),
            6_520_000.0 + a * 25.0 * math.sin(t) + b * 12.5 * math.sin(tv))


def write_cube(path, rotation=25.0, handed=1.0, skew=0.0, sorting="inline"):
    a, b, k = np.meshgrid(np.arange(NA), np.arange(NB), np.arange(NS), indexing="ij")
    depth = 1000.0 + 4.0 * k
    xs, ys = trace_xy(a, b, rotation, handed, skew)
    cx, cy = trace_xy(*APEX, rotation, handed, skew)
    values = (depth - (APEX_DEPTH + 0.002 * ((xs - cx) ** 2 + (ys - cy) ** 2))).astype(np.float32)
    spec = segyio.spec()
    spec.ilines = list(range(1000, 1000 + NA))
    spec.xlines = list(range(2000, 2000 + 2 * NB, 2))
    spec.samples = list(range(NS))
    spec.sorting = 2 if sorting == "inline" else 1
    spec.format = 5  # IEEE float
    with segyio.create(path, spec) as f:
        t = 0
        order = [(i, j) for i in range(NA) for j in range(NB)] if sorting == "inline" else \
            [(i, j) for j in range(NB) for i in range(NA)]
        for i, j in order:
            f.header[t] = {
                segyio.TraceField.INLINE_3D: spec.ilines[i],
                segyio.TraceField.CROSSLINE_3D: spec.xlines[j],
                segyio.TraceField.CDP_X: int(round(xs[i, j, 0] * 100)),
                segyio.TraceField.CDP_Y: int(round(ys[i, j, 0] * 100)),
                segyio.TraceField.SourceGroupScalar: -100,
                segyio.TraceField.DelayRecordingTime: 1000,
                segyio.TraceField.TRACE_SAMPLE_INTERVAL: 4000,
                segyio.TraceField.TRACE_SAMPLE_COUNT: NS,
            }
            f.trace[t] = values[i, j]
            t += 1
        f.bin.update(hns=NS, hdt=4000, tsort=spec.sorting)
    return path


def header_xy(path, il_index, xl_index):
    """What the headers say about the apex trace: its CDP_X / CDP_Y, scaled."""
    with segyio.open(path) as f:
        il, xl = f.ilines[il_index], f.xlines[xl_index]
        for t in range(f.tracecount):
            h = f.header[t]
            if h[segyio.TraceField.INLINE_3D] == il and h[segyio.TraceField.CROSSLINE_3D] == xl:
                s = h[segyio.TraceField.SourceGroupScalar]
                scale = 1.0 / abs(s) if s < 0 else (s or 1.0)
                return h[segyio.TraceField.CDP_X] * scale, h[segyio.TraceField.CDP_Y] * scale
    raise AssertionError("apex trace not found")


def apex_of(vol):
    v, f = gc.extract_isosurface(vol, 0.0)
    assert len(f) > 100
    return v[np.argmax(v[:, 2])]


def test_dome_renders_where_the_headers_say(tmp_path):
    path = str(write_cube(tmp_path / "dome.sgy"))
    vol = gc.Volume.from_segy(path)
    hx, hy = header_xy(path, *APEX)
    assert vol.rotation == pytest.approx(25.0, abs=1e-3)
    assert vol.spacing == pytest.approx((25.0, 12.5, 4.0), abs=1e-3)
    apex = apex_of(vol)
    assert abs(apex[0] - hx) < 0.5 and abs(apex[1] - hy) < 0.5, (apex, (hx, hy))
    assert apex[2] == pytest.approx(-APEX_DEPTH, abs=0.5)  # depth positive down -> z = -depth, apex on top
    # Top-down orthographic view centred on the headers' apex position: the nearest pixel is the apex.
    r = gc.Renderer(121, 121)
    half = 100.0  # metres either side (the corners stay inside the survey): 200 m over 121 pixels
    cam = gc.Camera.look_at((hx, hy, 0.0), (hx, hy, -2000.0), up=(0, 1, 0), projection="orthographic",
                            ortho_height=2 * half)
    res = r.render_isosurface(vol, 0.0, cam, culling="none")
    assert res.coverage.all()
    row, col = np.unravel_index(np.argmin(res.depth), res.depth.shape)
    px = 2 * half / 121
    x = hx - half + (col + 0.5) * px
    y = hy + half - (row + 0.5) * px
    assert math.hypot(x - hx, y - hy) < 3 * px, (row, col)
    assert res.depth.min() == pytest.approx(APEX_DEPTH, abs=2.0)  # eye at z = 0
    imp = r.render_isosurface(vol, 0.0, cam, culling="implicit")
    np.testing.assert_array_equal(imp.image, res.image)


@pytest.mark.parametrize("handed,sorting", [(-1.0, "inline"), (1.0, "crossline"), (-1.0, "crossline")])
def test_handedness_and_sorting(tmp_path, handed, sorting):
    path = str(write_cube(tmp_path / "c.sgy", rotation=-40.0, handed=handed, sorting=sorting))
    hx, hy = header_xy(path, *APEX)
    apex = apex_of(gc.Volume.from_segy(path))
    assert abs(apex[0] - hx) < 0.5 and abs(apex[1] - hy) < 0.5
    with segyio.open(path) as f:  # an open, memory-mapped file
        f.mmap()
        kw = gc.io.from_segy(f)
        assert kw["order"] == "xyz" and kw["z_positive"] == "down"
        apex2 = apex_of(gc.Volume(**kw))
    np.testing.assert_allclose(apex2, apex)


def test_skewed_survey_is_refused(tmp_path):
    path = str(write_cube(tmp_path / "skew.sgy", skew=math.radians(10.0)))
    with pytest.raises(gc.InputError, match="not perpendicular"):
        gc.Volume.from_segy(path)
    with pytest.raises(gc.InputError, match="neither a path nor an open segyio.SegyFile"):
        gc.io.from_segy(42)

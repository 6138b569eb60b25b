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

Issue 37 (SEG-Y as it comes):
- coordinates rounded to whole metres on 12.5 m bins load (default tolerance 10 % of a bin) and an
  explicit small ``tolerance`` refuses them; missing traces (left out of the file) and dead ones
  (trace identification code 2) are NaN, the geometry the complete file's;
- a truncated file, a binary header lying about the sample count, an unknown format code, a file
  too short for its headers and a missing file are InputErrors naming ``source``, the path and the
  cause;
- ``vol.inlines`` / ``crosslines`` / ``samples`` are segyio's own lists; ``add_slice(inline=...,
  crossline=..., time=..., depth=...)`` picks the nearest (the slice through that crossline's
  traces, also on a left-handed survey), out-of-range numbers list the range; sample 0 is the
  first (shallowest) sample; ``set_slice_index`` by number; pickling keeps the numbers;
- the Reek cubes (``../shared/data/reek/seismic``): the whole-metre cube loads with segyio's
  numbers, the dead-trace cube has its 656 dead traces as NaN.
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


def write_cube(path, rotation=25.0, handed=1.0, skew=0.0, sorting="inline", skip=(), dead=(), whole_metres=False):
    """The dome cube; ``skip``: (inline index, crossline index) of traces left out of the file,
    ``dead``: of traces written as dead (trace identification code 2, zeros); ``whole_metres``:
    CDP_X / CDP_Y rounded to whole metres (scalar 1) instead of centimetres."""
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
    spec.tracecount = NA * NB - len(skip)
    scale = 1 if whole_metres else 100
    with segyio.create(path, spec) as f:
        t = 0
        order = [(i, j) for i in range(NA) for j in range(NB)] if sorting == "inline" else \
            [(i, j) for j in range(NB) for i in range(NA)]
        for i, j in order:
            if (i, j) in skip:
                continue
            f.header[t] = {
                segyio.TraceField.INLINE_3D: spec.ilines[i],
                segyio.TraceField.CROSSLINE_3D: spec.xlines[j],
                segyio.TraceField.CDP_X: int(round(xs[i, j, 0] * scale)),
                segyio.TraceField.CDP_Y: int(round(ys[i, j, 0] * scale)),
                segyio.TraceField.SourceGroupScalar: 1 if whole_metres else -100,
                segyio.TraceField.DelayRecordingTime: 1000,
                segyio.TraceField.TRACE_SAMPLE_INTERVAL: 4000,
                segyio.TraceField.TRACE_SAMPLE_COUNT: NS,
                segyio.TraceField.TraceIdentificationCode: 2 if (i, j) in dead else 1,
            }
            f.trace[t] = np.zeros(NS, np.float32) if (i, j) in dead else values[i, j]
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


# ------------------------------------------------------------------ issue 37: SEG-Y as it comes


def test_whole_metre_coordinates_load_within_the_tolerance(tmp_path):
    # 12.5 m crossline bins, coordinates rounded to whole metres: up to 0.71 m off the grid.
    path = str(write_cube(tmp_path / "whole.sgy", rotation=25.0, whole_metres=True))
    vol = gc.Volume.from_segy(path)
    assert vol.spacing == pytest.approx((25.0, 12.5, 4.0), abs=0.02)
    assert vol.rotation == pytest.approx(25.0, abs=0.05)
    hx, hy = header_xy(path, *APEX)  # whole metres: within 0.71 m of the true apex
    apex = apex_of(vol)
    assert abs(apex[0] - hx) < 1.5 and abs(apex[1] - hy) < 1.5
    with pytest.raises(gc.InputError, match=f"^source: '{path}': the trace coordinates are not a regular grid"):
        gc.Volume.from_segy(path, tolerance=0.1)
    with pytest.raises(gc.InputError, match="^tolerance"):
        gc.Volume.from_segy(path, tolerance=-1.0)


def test_missing_and_dead_traces_are_no_data(tmp_path):
    skip = {(0, 0), (3, 5), (3, 6), (20, 30)}  # two corners of the survey among them
    dead = {(7, 7), (12, 17)}  # the apex trace is dead
    full = gc.io.from_segy(str(write_cube(tmp_path / "full.sgy", rotation=-40.0, handed=-1.0)))
    kw = gc.io.from_segy(str(write_cube(tmp_path / "holes.sgy", rotation=-40.0, handed=-1.0, skip=skip,
                                        dead=dead)))
    values = np.asarray(kw["values"])
    nan_traces = np.isnan(values).all(axis=2)
    want = np.zeros((NA, NB), bool)
    for i, j in skip | dead:
        want[i, j] = True
    np.testing.assert_array_equal(nan_traces, want)
    assert not np.isnan(values[~want]).any()
    np.testing.assert_array_equal(values[~want], np.asarray(full["values"])[~want])
    # The geometry from the traces present (fitted to centimetre coordinates: the same to a millimetre).
    for key, atol in (("origin", 1e-3), ("spacing", 1e-5), ("rotation", 1e-4)):
        np.testing.assert_allclose(kw[key], full[key], atol=atol)
    assert kw["yflip"] and full["yflip"]
    np.testing.assert_array_equal(kw["inlines"], full["inlines"])
    np.testing.assert_array_equal(kw["crosslines"], full["crosslines"])
    vol = gc.Volume(**kw)
    np.testing.assert_allclose(vol.bounds, gc.Volume(**full).bounds, atol=2e-3)


def segy_bytes(tmp_path):
    path = write_cube(tmp_path / "ok.sgy")
    return path.read_bytes()


@pytest.mark.parametrize("damage", ["truncated", "sample count", "format code", "tiny", "missing"])
def test_reader_failures_are_input_errors_naming_the_path(tmp_path, damage):
    import struct

    data = bytearray(segy_bytes(tmp_path))
    path = tmp_path / f"{damage.replace(' ', '_')}.sgy"
    if damage == "truncated":
        data = data[:-1000]
        cause = "trace count inconsistent with file size"
    elif damage == "sample count":  # the binary header lies about the samples per trace
        data[3220:3222] = struct.pack(">h", NS + 7)
        cause = "trace count inconsistent with file size"
    elif damage == "format code":
        data[3224:3226] = struct.pack(">h", 77)
        cause = "sample format code is 77"
    elif damage == "tiny":
        data = data[:1000]
        cause = "cannot read the SEG-Y file"
    else:
        cause = "no such file"
    if damage != "missing":
        path.write_bytes(bytes(data))
    with pytest.raises(gc.InputError) as e:
        gc.Volume.from_segy(path)
    msg = str(e.value)
    assert msg.startswith("source: ") and repr(str(path)) in msg and cause in msg, msg


def test_survey_numbers_and_slices_in_survey_numbers(tmp_path):
    path = str(write_cube(tmp_path / "lh.sgy", rotation=-40.0, handed=-1.0))  # left-handed
    vol = gc.Volume.from_segy(path)
    with segyio.open(path) as f:
        np.testing.assert_array_equal(vol.inlines, f.ilines)
        np.testing.assert_array_equal(vol.crosslines, f.xlines)
        np.testing.assert_array_equal(vol.samples, f.samples)
        il, xl, samples = list(f.ilines), list(f.xlines), list(f.samples)
    assert samples[0] == 1000.0 and samples[1] == 1004.0
    s = gc.Scene()

    def plane(**kw):
        i = s.add_slice(vol, **kw)
        v = s.geometry(i)[0]
        s.remove(i)
        return v

    # Inline number -> its index in segyio's list; crossline index 0 = the file's first crossline
    # (left-handed: the stored grid runs the other way), sample 0 = the first (shallowest) sample.
    np.testing.assert_array_equal(plane(inline=il[12]), plane(axis="inline", index=12))
    np.testing.assert_array_equal(plane(inline=il[12] + 0.4), plane(axis="inline", index=12))  # nearest
    for j in (0, 17):
        v = plane(crossline=xl[j])
        np.testing.assert_array_equal(v, plane(axis="crossline", index=j))
        hx, hy = header_xy(path, 12, j)  # the slice passes through that crossline's traces
        assert np.hypot(v[:, 0] - hx, v[:, 1] - hy).min() < 0.01
    top = plane(axis="sample", index=0)
    np.testing.assert_allclose(top[:, 2], -1000.0)
    np.testing.assert_allclose(plane(time=1009.0)[:, 2], -1008.0)  # nearest sample: 1008
    np.testing.assert_allclose(plane(depth=samples[-1])[:, 2], -samples[-1])
    with pytest.raises(gc.InputError, match=r"^inline: 900 is outside the volume's inlines 1000\.\.1020"):
        s.add_slice(vol, inline=900)
    with pytest.raises(gc.InputError,
                       match=r"^crossline: 2100 is outside the volume's crosslines 2000\.\.2060 \(step 2, 31 values"):
        s.add_slice(vol, crossline=2100)
    with pytest.raises(gc.InputError, match=r"^time: 2000 is outside the volume's times 1000\.\.1236"):
        s.add_slice(vol, time=2000.0)
    with pytest.raises(gc.InputError, match="^crossline: give one of"):
        s.add_slice(vol, inline=1000, crossline=2000)
    with pytest.raises(gc.InputError, match="^index: 60 is outside 0..59"):
        s.add_slice(vol, "sample", 60)
    # moving a slice by number along its axis
    sl = s.add_slice(vol, "sample", 0)
    s.set_slice_index(sl, time=1100.0)
    np.testing.assert_allclose(s.geometry(sl)[0][:, 2], -1100.0)
    s.set_slice_index(sl, 2)
    np.testing.assert_allclose(s.geometry(sl)[0][:, 2], -1008.0)
    with pytest.raises(gc.InputError, match="^inline: this slice lies along axis 2"):
        s.set_slice_index(sl, inline=1000)
    # numbers survive pickling; a volume without numbers says so
    import pickle

    again = pickle.loads(pickle.dumps(vol))
    np.testing.assert_array_equal(again.crosslines, vol.crosslines)
    sl2 = s.add_slice(again, crossline=xl[0])
    np.testing.assert_array_equal(s.geometry(sl2)[0], plane(axis="crossline", index=0))
    plain = gc.Volume(np.zeros((3, 4, 5), np.float32), order="xyz")
    assert plain.inlines is None and plain.samples is None
    with pytest.raises(gc.InputError, match="^inline: the volume has no inline numbers"):
        s.add_slice(plain, inline=3)


def test_sample_zero_is_the_first_sample_of_a_depth_volume():
    # Depth positive down (z0 = 100 m, 10 m a sample): sample 0 is the shallowest, at z = -100;
    # z up: sample 0 is z0, the lowest, as before.
    s = gc.Scene()
    down = gc.Volume(np.zeros((3, 4, 5), np.float32), origin=(0, 0, 100), spacing=(1, 1, 10), order="xyz",
                     z_positive="down")
    up = gc.Volume(np.zeros((3, 4, 5), np.float32), origin=(0, 0, 100), spacing=(1, 1, 10), order="xyz")
    for vol, k, z in ((down, 0, -100.0), (down, 4, -140.0), (up, 0, 100.0), (up, 4, 140.0)):
        i = s.add_slice(vol, "sample", k)
        np.testing.assert_allclose(s.geometry(i)[0][:, 2], z)
    # a lens box counts the same way: samples 0..1 of the depth volume are its top two
    lens = gc.Scene()
    lens.add_lens(down, ((0, 2), (0, 3), (0, 1)))
    assert lens.bounds == ((0.0, 0.0, -110.0), (2.0, 3.0, -100.0))


REEK = __import__("pathlib").Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "reek" / "seismic"


@pytest.mark.skipif(not REEK.is_dir(), reason="../shared/data/reek not present")
def test_reek_cubes():
    ex2 = REEK / "ex2_complete_3d_75x71x26.segy"  # whole-metre CDP coordinates on 12.5 m bins
    vol = gc.Volume.from_segy(ex2)
    assert vol.shape == (26, 71, 75)
    assert vol.spacing == pytest.approx((12.5, 12.5, 4.0), abs=0.01)
    with segyio.open(ex2) as f:
        np.testing.assert_array_equal(vol.inlines, f.ilines)
        np.testing.assert_array_equal(vol.crosslines, f.xlines)
        np.testing.assert_array_equal(vol.samples, f.samples)
        x0 = f.header[0][segyio.TraceField.CDP_X]
        y0 = f.header[0][segyio.TraceField.CDP_Y]
    s = gc.Scene()
    v = s.geometry(s.add_slice(vol, inline=int(vol.inlines[0])))[0]
    assert np.hypot(v[:, 0] - x0, v[:, 1] - y0).min() < 1.0  # the first trace lies on the first inline
    dead = gc.io.from_segy(REEK / "cube_w_deadtraces.segy")
    with segyio.open(REEK / "cube_w_deadtraces.segy") as f:
        trid = f.attributes(segyio.TraceField.TraceIdentificationCode)[:]
    nan_traces = np.isnan(np.asarray(dead["values"])).all(axis=2)
    assert nan_traces.sum() == (trid == 2).sum() == 656

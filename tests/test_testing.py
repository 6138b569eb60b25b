"""geocull.testing: assert_images_close (fails with a diff file on a one-pixel change beyond the
tolerance, passes within it), the PNG reader (Pillow: the test extra; skipped without it), and the
pytest plugin's image_regression fixture driven through pytester."""

from __future__ import annotations

import zlib
from pathlib import Path

import numpy as np
import pytest

from geocull.testing import assert_images_close, image_difference, read_png, write_png

pytest.importorskip("PIL", reason="geocull.testing reads PNG files with Pillow: pip install 'geocull[test]'")

pytest_plugins = ["pytester"]


def image(h=12, w=16, seed=0):
    rng = np.random.default_rng(seed)
    img = rng.integers(0, 256, size=(h, w, 4), dtype=np.uint8)
    img[..., 3] = 255
    return img


def test_one_pixel_beyond_tolerance_fails_with_diff_files(tmp_path):
    a = image()
    b = a.copy()
    b[5, 7, 1] = (int(b[5, 7, 1]) + 9) % 256 if b[5, 7, 1] < 200 else int(b[5, 7, 1]) - 9
    assert_images_close(a, a.copy())
    assert_images_close(a, b, tol=9)  # within the tolerance
    assert_images_close(a, b, max_differing=1)  # one pixel allowed
    with pytest.raises(AssertionError) as e:
        assert_images_close(a, b, tol=8, out_dir=tmp_path, name="case")
    msg = str(e.value)
    assert "differ in 1 of 192 pixels" in msg and "(5, 7)" in msg and str(tmp_path) in msg
    diff = read_png(tmp_path / "case-diff.png")
    red = np.all(diff[..., :3] == (255, 0, 0), axis=2)
    assert red.sum() == 1 and red[5, 7]
    np.testing.assert_array_equal(read_png(tmp_path / "case-actual.png"), a)
    np.testing.assert_array_equal(read_png(tmp_path / "case-expected.png"), b)


def test_sizes_rgb_and_render_results(tmp_path):
    a = image()
    with pytest.raises(AssertionError, match="sizes differ"):
        assert_images_close(a, a[:-1], out_dir=tmp_path)
    assert (tmp_path / "image-actual.png").exists()
    assert_images_close(a[..., :3], a)  # RGB is RGBA with alpha 255

    class Result:
        image = a

    assert_images_close(Result(), write_png(tmp_path / "b.png", a))  # objects with .image, PNG paths
    d = image_difference(a, a)
    assert d["n_differing"] == 0 and d["first"] is None


def _png(img: np.ndarray, filters: list[int]) -> bytes:
    """A PNG of RGB ``img`` with the given filter type per row (to test the reader's filters)."""
    import struct

    h, w, c = img.shape
    bpp, raw, prev = c, b"", np.zeros(w * c, np.int32)
    for r in range(h):
        line = img[r].reshape(-1).astype(np.int32)
        f = filters[r % len(filters)]
        left = np.r_[np.zeros(bpp, np.int32), line[:-bpp]]
        ul = np.r_[np.zeros(bpp, np.int32), prev[:-bpp]]
        if f == 0:
            out = line
        elif f == 1:
            out = line - left
        elif f == 2:
            out = line - prev
        elif f == 3:
            out = line - (left + prev) // 2
        else:
            p = left + prev - ul
            pa, pb, pc = abs(p - left), abs(p - prev), abs(p - ul)
            out = line - np.where((pa <= pb) & (pa <= pc), left, np.where(pb <= pc, prev, ul))
        raw += bytes([f]) + (out & 255).astype(np.uint8).tobytes()
        prev = line

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def test_read_png_every_filter(tmp_path):
    img = image(9, 7)[..., :3]
    p = tmp_path / "f.png"
    p.write_bytes(_png(img, [0, 1, 2, 3, 4]))
    got = read_png(p)
    np.testing.assert_array_equal(got[..., :3], img)
    assert (got[..., 3] == 255).all()


def test_png_round_trips_rgba_rgb_grey_and_16_bit(tmp_path):
    from PIL import Image

    rgba = image(11, 13, seed=3)
    rgba[..., 3] = np.random.default_rng(4).integers(0, 256, size=rgba.shape[:2], dtype=np.uint8)
    np.testing.assert_array_equal(read_png(write_png(tmp_path / "rgba.png", rgba)), rgba)  # geocull's writer
    Image.fromarray(rgba, "RGBA").save(tmp_path / "rgba_pil.png")
    np.testing.assert_array_equal(read_png(tmp_path / "rgba_pil.png"), rgba)  # Pillow's writer (its filters)

    rgb = rgba[..., :3].copy()
    Image.fromarray(rgb, "RGB").save(tmp_path / "rgb.png")
    got = read_png(tmp_path / "rgb.png")
    np.testing.assert_array_equal(got[..., :3], rgb)
    assert (got[..., 3] == 255).all()
    Image.fromarray(rgb, "RGB").save(tmp_path / "rgb_interlaced.png", interlace=1)  # Adam7: not read before
    np.testing.assert_array_equal(read_png(tmp_path / "rgb_interlaced.png")[..., :3], rgb)

    grey = rgba[..., 0].copy()
    Image.fromarray(grey, "L").save(tmp_path / "grey.png")
    np.testing.assert_array_equal(read_png(tmp_path / "grey.png")[..., :3], np.dstack([grey] * 3))

    grey16 = grey.astype(np.uint16) * 256 + 7  # high byte == grey
    Image.fromarray(grey16).save(tmp_path / "grey16.png")
    assert Image.open(tmp_path / "grey16.png").mode.startswith("I")  # really 16 bits on file
    np.testing.assert_array_equal(read_png(tmp_path / "grey16.png")[..., :3], np.dstack([grey] * 3))

    (tmp_path / "no.png").write_bytes(b"GIF89a not a png")
    with pytest.raises(ValueError, match="not a PNG file"):
        read_png(tmp_path / "no.png")


def test_read_png_without_pillow_says_which_extra(tmp_path, monkeypatch):
    import sys

    p = write_png(tmp_path / "a.png", image())  # writing needs no Pillow
    monkeypatch.setitem(sys.modules, "PIL", None)  # import PIL fails
    with pytest.raises(ImportError, match=r"Pillow.*geocull\[test\]"):
        read_png(p)
    assert_images_close(image(), image())  # arrays compare without Pillow


def test_rendered_image_round_trips_through_png(tmp_path, renderer_small):
    import geocull as gc

    s = gc.Scene()
    s.add_heightfield(np.random.default_rng(1).normal(size=(9, 9)), spacing=(10, 10), color=(0.2, 0.6, 0.3))
    res = renderer_small(32, 24).render(s, gc.Camera.fit(s, aspect=32 / 24))
    res.save_png(str(tmp_path / "r.png"))
    assert_images_close(res, tmp_path / "r.png")


PLUGIN_TEST = """
import numpy as np

def img(v):
    a = np.zeros((6, 8, 4), np.uint8)
    a[..., 3] = 255
    a[2, 3, 0] = v
    return a

def test_view(image_regression):
    image_regression.check(img(VALUE), tol=TOL)

def test_named(image_regression):
    image_regression.check(img(0), name="first")
    image_regression.check(img(0)[..., :3], name="second")
"""


def _write(pytester, value, tol=0):
    pytester.makepyfile(test_views=PLUGIN_TEST.replace("VALUE", str(value)).replace("TOL", str(tol)))


def test_pytest_plugin_baselines(pytester):
    _write(pytester, 0)
    r = pytester.runpytest()  # no baselines yet: a failure saying how to write them
    r.assert_outcomes(failed=2)
    r.stdout.fnmatch_lines(["*no baseline image*--geocull-update-baselines*"])

    r = pytester.runpytest("--geocull-update-baselines")
    r.assert_outcomes(passed=2)
    base = Path(pytester.path) / "baselines" / "test_views"
    assert sorted(p.name for p in base.iterdir()) == ["test_named-first.png", "test_named-second.png",
                                                       "test_view.png"]
    pytester.runpytest().assert_outcomes(passed=2)

    _write(pytester, 50)  # one pixel changes by 50
    out = Path(pytester.path) / "imgs"
    r = pytester.runpytest("--geocull-image-out", str(out))
    r.assert_outcomes(passed=1, failed=1)
    r.stdout.fnmatch_lines(["*images differ in 1 of 48 pixels*"])
    assert (out / "test_view" / "test_view-diff.png").exists()
    _write(pytester, 50, tol=50)  # within the tolerance
    pytester.runpytest().assert_outcomes(passed=2)

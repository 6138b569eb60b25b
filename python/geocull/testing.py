"""Image-regression testing: :func:`assert_images_close` and the pytest plugin.

``assert_images_close(actual, expected, max_differing=0, tol=0)`` compares two images pixel by
pixel and, on failure, writes ``<name>-actual.png``, ``<name>-expected.png`` and ``<name>-diff.png``
(differing pixels in red over a dimmed grey copy of the expected image) and says where, how many
pixels differ and by how much.

The pytest plugin (registered through the ``pytest11`` entry point, so it is active wherever
geocull is installed) adds the ``image_regression`` fixture::

    def test_view(image_regression, renderer):
        res = renderer.render(scene, camera)
        image_regression.check(res, max_differing=10, tol=2)

Baselines live beside the test file, in ``baselines/<test module>/<test name>[-<name>].png``;
``pytest --geocull-update-baselines`` (re)writes them instead of comparing. A missing baseline is
a failure that says how to write it. On failure the three PNGs go to the test's ``tmp_path`` (or
to ``--geocull-image-out DIR``).
"""

from __future__ import annotations

import os
import re
import struct
import tempfile
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from .results import encode_png

__all__ = [
    "assert_images_close",
    "image_difference",
    "read_png",
    "write_png",
    "ImageRegression",
    "UPDATE_OPTION",
]

#: The command-line flag that (re)writes baselines.
UPDATE_OPTION = "--geocull-update-baselines"
_OUT_OPTION = "--geocull-image-out"


def _rgba(x: Any, arg: str) -> np.ndarray:
    """(H, W, 4) uint8 of an image: an array (H, W) grey, (H, W, 3) RGB or (H, W, 4) RGBA, uint8
    (floats in [0, 1] are scaled), an object with ``.image`` (a RenderResult), or a PNG path."""
    if isinstance(x, (str, os.PathLike)):
        return read_png(x)
    a = np.asarray(getattr(x, "image", x))
    if a.dtype.kind == "f":
        a = np.clip(np.round(a * 255.0), 0, 255).astype(np.uint8)
    if a.dtype != np.uint8:
        raise TypeError(f"{arg}: expected a uint8 image (or floats in [0, 1]), got dtype {a.dtype}")
    if a.ndim == 2:
        a = np.repeat(a[:, :, None], 3, axis=2)
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise TypeError(f"{arg}: expected an (H, W), (H, W, 3) or (H, W, 4) image, got shape {a.shape}")
    if a.shape[2] == 3:
        a = np.concatenate([a, np.full(a.shape[:2] + (1,), 255, np.uint8)], axis=2)
    return np.ascontiguousarray(a)


def write_png(path: str | os.PathLike[str], image: Any) -> Path:
    """Write ``image`` (as :func:`assert_images_close` accepts it) to ``path`` as an RGBA PNG."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_bytes(encode_png(_rgba(image, "image")))
    return p


def read_png(path: str | os.PathLike[str]) -> np.ndarray:
    """(H, W, 4) uint8 RGBA of an 8-bit, non-interlaced PNG file (grey, grey + alpha, RGB or RGBA;
    every filter type), such as the ones :func:`write_png` and ``RenderResult.save_png`` write."""
    data = Path(path).read_bytes()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{path}: not a PNG file")
    pos, idat, hdr = 8, [], None
    while pos + 8 <= len(data):
        (n,) = struct.unpack(">I", data[pos:pos + 4])
        tag, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + n]
        pos += 12 + n
        if tag == b"IHDR":
            hdr = struct.unpack(">IIBBBBB", body)
        elif tag == b"IDAT":
            idat.append(body)
        elif tag == b"IEND":
            break
    if hdr is None:
        raise ValueError(f"{path}: no IHDR chunk")
    w, h, depth, ctype, _, _, interlace = hdr
    channels = {0: 1, 2: 3, 4: 2, 6: 4}.get(ctype)
    if depth != 8 or channels is None or interlace:
        raise ValueError(f"{path}: only 8-bit, non-interlaced grey/RGB/RGBA PNGs are read (bit depth {depth}, "
                         f"colour type {ctype}, interlace {interlace})")
    raw = np.frombuffer(zlib.decompress(b"".join(idat)), np.uint8)
    stride = w * channels
    rows = raw.reshape(h, stride + 1)
    out = np.zeros((h, stride), np.uint8)
    prev = np.zeros(stride, np.uint8)
    bpp = channels
    for r in range(h):
        f, line = rows[r, 0], rows[r, 1:].copy()
        if f == 1:  # Sub: running sums per channel, modulo 256
            line = np.cumsum(line.reshape(w, bpp), axis=0, dtype=np.uint8).reshape(stride)
        elif f == 2:  # Up
            line = line + prev
        elif f in (3, 4):  # Average, Paeth: sequential along the row
            cur = line.astype(np.int32)
            up = prev.astype(np.int32)
            for i in range(stride):
                left = cur[i - bpp] if i >= bpp else 0
                if f == 3:
                    cur[i] = (cur[i] + (left + up[i]) // 2) & 255
                else:
                    ul = up[i - bpp] if i >= bpp else 0
                    p = left + up[i] - ul
                    pa, pb, pc = abs(p - left), abs(p - up[i]), abs(p - ul)
                    pred = left if pa <= pb and pa <= pc else (up[i] if pb <= pc else ul)
                    cur[i] = (cur[i] + pred) & 255
            line = cur.astype(np.uint8)
        elif f != 0:
            raise ValueError(f"{path}: bad filter type {f} in row {r}")
        out[r] = line
        prev = line
    img = out.reshape(h, w, channels)
    return _rgba(img if channels != 2 else np.dstack([img[..., 0]] * 3 + [img[..., 1]]), "image")


def image_difference(actual: Any, expected: Any, tol: int = 0) -> dict[str, Any]:
    """How two images differ: ``mask`` (H, W) bool, pixels where some channel (RGBA) differs by more
    than ``tol`` (0..255); ``n_differing``; ``max_difference`` (largest channel difference);
    ``first`` (row, col) of the first differing pixel in row-major order or None; ``worst``
    (row, col) of the largest difference or None. The images must have the same shape."""
    a, e = _rgba(actual, "actual"), _rgba(expected, "expected")
    if a.shape != e.shape:
        raise ValueError(f"actual is {a.shape[1]}x{a.shape[0]} pixels, expected {e.shape[1]}x{e.shape[0]}")
    d = np.abs(a.astype(np.int16) - e.astype(np.int16)).max(axis=2)
    mask = d > int(tol)
    n = int(mask.sum())
    first = tuple(int(v) for v in np.argwhere(mask)[0]) if n else None
    worst = tuple(int(v) for v in np.unravel_index(int(np.argmax(d)), d.shape)) if n else None
    return dict(mask=mask, n_differing=n, max_difference=int(d.max()) if d.size else 0, first=first, worst=worst)


def _diff_image(expected: np.ndarray, mask: np.ndarray) -> np.ndarray:
    grey = (expected[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)) * 0.35
    out = np.repeat(grey.astype(np.uint8)[:, :, None], 3, axis=2)
    out[mask] = (255, 0, 0)
    return out


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "image"


def assert_images_close(
    actual: Any,
    expected: Any,
    max_differing: int = 0,
    tol: int = 0,
    out_dir: str | os.PathLike[str] | None = None,
    name: str = "image",
) -> None:
    """Assert that ``actual`` and ``expected`` differ in at most ``max_differing`` pixels, a pixel
    differing when one of its channels (RGBA, 0..255) differs by more than ``tol``.

    Images: (H, W) / (H, W, 3) / (H, W, 4) uint8 arrays (floats in [0, 1] are scaled), anything with
    an ``.image`` (a :class:`geocull.RenderResult`) or a path to a PNG file. On failure (also when
    the sizes differ) ``<name>-actual.png``, ``<name>-expected.png`` and ``<name>-diff.png``
    (differing pixels red on a dimmed grey expected image) are written to ``out_dir`` (default: a
    new temporary directory) and the AssertionError says where, how many pixels differ, the
    largest channel difference and the first and worst pixels (row, col)."""
    a, e = _rgba(actual, "actual"), _rgba(expected, "expected")
    max_differing, tol = int(max_differing), int(tol)
    if max_differing < 0 or not (0 <= tol <= 255):
        raise ValueError(f"max_differing ({max_differing}) must be >= 0 and tol ({tol}) in 0..255")
    if a.shape == e.shape:
        d = image_difference(a, e, tol)
        if d["n_differing"] <= max_differing:
            return
        what = (f"images differ in {d['n_differing']} of {a.shape[0] * a.shape[1]} pixels (allowed {max_differing}, "
                f"tol {tol}); largest channel difference {d['max_difference']} at (row, col) {d['worst']}, "
                f"first at {d['first']}")
        diff = _diff_image(e, d["mask"])
    else:
        what = f"image sizes differ: actual {a.shape[1]}x{a.shape[0]}, expected {e.shape[1]}x{e.shape[0]} pixels"
        diff = None
    out = Path(out_dir) if out_dir is not None else Path(tempfile.mkdtemp(prefix="geocull-images-"))
    stem = _safe(name)
    paths = [write_png(out / f"{stem}-actual.png", a), write_png(out / f"{stem}-expected.png", e)]
    if diff is not None:
        paths.append(write_png(out / f"{stem}-diff.png", diff))
    raise AssertionError(f"{what}; wrote {', '.join(p.name for p in paths)} to {out}")


class ImageRegression:
    """What the ``image_regression`` fixture hands a test: :meth:`check` compares an image with the
    test's baseline PNG (or writes it with ``--geocull-update-baselines``)."""

    def __init__(self, baseline_dir: Path, test_name: str, out_dir: Path, update: bool) -> None:
        self.baseline_dir = baseline_dir
        self.test_name = _safe(test_name)
        self.out_dir = out_dir
        self.update = update
        self.written: list[Path] = []

    def baseline_path(self, name: str | None = None) -> Path:
        """``<test dir>/baselines/<module>/<test>[-<name>].png``."""
        stem = self.test_name if name is None else f"{self.test_name}-{_safe(name)}"
        return self.baseline_dir / f"{stem}.png"

    def check(self, image: Any, name: str | None = None, max_differing: int = 0, tol: int = 0) -> None:
        """Compare ``image`` (as :func:`assert_images_close` takes it) with the baseline ``name``
        (None: the test's only one) within ``max_differing`` pixels and ``tol`` per channel."""
        path = self.baseline_path(name)
        if self.update:
            self.written.append(write_png(path, image))
            return
        label = path.stem
        if not path.exists():
            got = write_png(self.out_dir / f"{label}-actual.png", image)
            raise AssertionError(
                f"no baseline image {path}; run pytest with {UPDATE_OPTION} to write it (this run's image: {got})"
            )
        assert_images_close(image, path, max_differing=max_differing, tol=tol, out_dir=self.out_dir, name=label)


# --------------------------------------------------------------------------- pytest plugin (pytest11)


def pytest_addoption(parser: Any) -> None:
    """The plugin's options: ``--geocull-update-baselines`` and ``--geocull-image-out DIR``."""
    group = parser.getgroup("geocull", "geocull image regression")
    group.addoption(UPDATE_OPTION, action="store_true", default=False,
                    help="write the image_regression baselines instead of comparing against them")
    group.addoption(_OUT_OPTION, default=None, metavar="DIR",
                    help="where failing image comparisons write their PNGs (default: the test's tmp_path)")


def _image_regression(request: Any, tmp_path: Path) -> ImageRegression:
    """geocull's image-regression fixture: ``image_regression.check(image, name=None,
    max_differing=0, tol=0)`` compares with ``baselines/<module>/<test>[-<name>].png`` beside the
    test file; ``--geocull-update-baselines`` writes them instead."""
    cfg = request.config
    test_file = Path(str(request.node.path))
    base = test_file.parent / "baselines" / test_file.stem
    out = cfg.getoption(_OUT_OPTION)
    out_dir = Path(out) / _safe(request.node.name) if out else tmp_path
    return ImageRegression(base, request.node.name, out_dir, bool(cfg.getoption(UPDATE_OPTION)))


try:  # the fixture exists where pytest does; geocull.testing's functions work without it
    import pytest as _pytest
except ImportError:  # pragma: no cover - pytest absent
    pass
else:
    image_regression = _pytest.fixture(name="image_regression")(_image_regression)

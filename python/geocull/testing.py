"""Image-regression testing: :func:`assert_images_close` and the pytest plugin.

``assert_images_close(actual, expected, max_differing=0, tol=0)`` compares two images pixel by
pixel and, on failure, writes ``<name>-actual.png``, ``<name>-expected.png`` and ``<name>-diff.png``
(differing pixels in red over a dimmed grey copy of the expected image) and says where, how many
pixels differ and by how much. PNG files are written without dependencies
(:func:`geocull.results.encode_png`) and read with Pillow (:func:`read_png`; the ``test`` extra),
imported only when a PNG file is read.

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
import tempfile
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


def _pillow_image() -> Any:
    """Pillow's ``PIL.Image``, imported on first use: reading PNG files needs it (writing does not)."""
    try:
        from PIL import Image
    except ImportError as e:
        raise ImportError(
            "geocull.testing reads PNG files (baselines, read_png) with Pillow, which is not installed: "
            "pip install 'geocull[test]' (the test extra) or pip install pillow"
        ) from e
    return Image


def read_png(path: str | os.PathLike[str]) -> np.ndarray:
    """(H, W, 4) uint8 RGBA of a PNG file, such as the ones :func:`write_png` and
    ``RenderResult.save_png`` write: grey, grey + alpha, RGB, RGBA or palette, 8 or 16 bits per
    channel (16-bit grey keeps its high byte; Pillow reads 16-bit colour as 8-bit), interlaced or
    not. Read with Pillow (the ``test`` extra), imported on first use: an ImportError that says so
    where it is missing. A file that is not a PNG raises ValueError."""
    Image = _pillow_image()
    try:
        img = Image.open(path, formats=["PNG"])
    except Image.UnidentifiedImageError as e:
        raise ValueError(f"{path}: not a PNG file") from e
    with img:
        img.load()
        if img.mode in ("I;16", "I;16B", "I;16L", "I"):  # 16-bit grey: its high byte
            a = np.asarray(img).astype(np.uint32) >> 8
            return _rgba(np.clip(a, 0, 255).astype(np.uint8), "image")
        return _rgba(np.asarray(img.convert("RGBA")), "image")


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

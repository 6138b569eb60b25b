"""A sub-surface scene from data as it comes: xtgeo horizons, a SEG-Y cube (segyio), trimesh faults
and a well (issue 16).

The first half writes a small synthetic survey to disk in the formats a user receives: three
horizons as IRAP binary grids (xtgeo; rotated 30°, depth positive down, one with an undefined hole),
a depth cube as SEG-Y (segyio; the same rotated survey, CDP_X / CDP_Y headers with a scalar) holding
a salt dome, two faults and a well path as PLY meshes (trimesh). The second half, ``build_scene``,
is what a user writes: every source goes in with one call, conventions (rotation, yflip, depth
positive down, (inline, crossline, sample) order, undefined values) are translated by geocull.

Glue per data source in ``build_scene`` (the lines marked ``# glue:``, printed at the end; the
``for`` over the user's own file list not counted): xtgeo horizons 1 (read + convert + add in one
call), segyio cube 2 (read the cube; its isosurface into the scene), trimesh faults 1 and well 1.

    python examples/geodata_scene.py [--out examples/out/geodata] [--width 800 --height 600] [--quick]

Writes ``scene.png`` (culling="horizon", the unculled image; checked equal) and prints the scene.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import segyio
import trimesh
import xtgeo

import geocull as gc

# The survey: origin, rotation (degrees counter-clockwise), node spacing along its axes, node counts.
X0, Y0, ROT, DX, DY, NI, NJ = 461_000.0, 5_930_000.0, 30.0, 25.0, 30.0, 80, 60


def survey_xy(i: np.ndarray, j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World (x, y) of survey node (i, j) (xtgeo's convention, yflip 1)."""
    c, s = math.cos(math.radians(ROT)), math.sin(math.radians(ROT))
    return X0 + i * DX * c - j * DY * s, Y0 + i * DX * s + j * DY * c


def dome_depth(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    cx, cy = survey_xy(np.asarray(50.0), np.asarray(28.0))
    return np.asarray(1500.0 + 0.0009 * ((x - cx) ** 2 + (y - cy) ** 2))


def write_data(d: Path) -> tuple[list[Path], Path, list[Path], Path]:
    """The synthetic survey as files: horizons (.gri), cube (.sgy), faults and well (.ply)."""
    i, j = np.meshgrid(np.arange(NI), np.arange(NJ), indexing="ij")  # xtgeo's (ncol, nrow)
    horizons = []
    for k, (name, base) in enumerate([("TopA", 1620.0), ("TopB", 1720.0), ("TopC", 1840.0)]):
        depth = base + 25.0 * np.sin(i / 11.0 + k) * np.cos(j / 8.0) + 0.4 * i
        mask = ((i - 20) ** 2 + (j - 40) ** 2 < 30) if k == 0 else np.zeros_like(i, bool)  # undefined nodes
        surf = xtgeo.RegularSurface(ncol=NI, nrow=NJ, xinc=DX, yinc=DY, xori=X0, yori=Y0, rotation=ROT,
                                    values=np.ma.MaskedArray(depth, mask=mask), name=name)
        horizons.append(d / f"{name}.gri")
        surf.to_file(horizons[-1], fformat="irap_binary")

    # The cube: inline = survey column i, crossline = row j, depth samples every 10 m from 1400 m.
    na, nb, ns, z0, dz = NI // 2, NJ // 2, 70, 1400.0, 10.0
    a, b = np.meshgrid(np.arange(na), np.arange(nb), indexing="ij")
    tx, ty = survey_xy(2.0 * a, 2.0 * b)
    depth = z0 + dz * np.arange(ns)
    values = (depth[None, None, :] - dome_depth(tx, ty)[..., None]).astype(np.float32)
    spec = segyio.spec()
    spec.ilines, spec.xlines, spec.samples = list(range(1, na + 1)), list(range(1, nb + 1)), list(range(ns))
    spec.sorting, spec.format = 2, 5
    cube = d / "dome.sgy"
    with segyio.create(str(cube), spec) as f:
        for t, (ia, ib) in enumerate((p, q) for p in range(na) for q in range(nb)):
            f.header[t] = {segyio.TraceField.INLINE_3D: ia + 1, segyio.TraceField.CROSSLINE_3D: ib + 1,
                           segyio.TraceField.CDP_X: int(round(tx[ia, ib] * 100)),
                           segyio.TraceField.CDP_Y: int(round(ty[ia, ib] * 100)),
                           segyio.TraceField.SourceGroupScalar: -100,
                           segyio.TraceField.DelayRecordingTime: int(z0),
                           segyio.TraceField.TRACE_SAMPLE_INTERVAL: int(dz * 1000)}
            f.trace[t] = values[ia, ib]
        f.bin.update(hns=ns, hdt=int(dz * 1000), tsort=2)

    faults = []
    for n, (fi, dip) in enumerate([(30.0, 0.35), (62.0, -0.3)]):
        nu, nv = 30, 12
        u, w = np.meshgrid(np.linspace(-2, NJ + 2, nu), np.linspace(1600.0, 2000.0, nv))
        fx, fy = survey_xy(fi + dip * (w - 1600.0) / DX, u)
        m = trimesh.Trimesh(np.stack([fx, fy, -w], axis=-1).reshape(-1, 3), gc.data.grid_faces(nu, nv), process=False)
        faults.append(d / f"fault{n}.ply")
        m.export(faults[-1])
    wx, wy = (float(v) for v in survey_xy(np.asarray(45.0), np.asarray(35.0)))
    path = np.array([(wx, wy, -1300.0), (wx + 150.0, wy, -2050.0)])
    well = trimesh.creation.cylinder(radius=12.0, segment=path, sections=12)
    well_path = d / "well.ply"
    well.export(well_path)
    return horizons, cube, faults, well_path


def build_scene(horizons: Sequence[Path], cube: Path, faults: Sequence[Path], well: Path) -> gc.Scene:
    """What a user writes: one call per source (the glue counted in the module doc)."""
    scene = gc.Scene()
    for h in horizons:  # xtgeo: rotation, yflip, undefined nodes, depth positive down
        scene.add_heightfield(**gc.io.from_xtgeo_surface(xtgeo.surface_from_file(h)), tiles=(8, 6))  # glue: xtgeo
    dome = gc.Volume.from_segy(cube)  # glue: segyio (inline/crossline/sample, headers, rotation, depth down)
    scene.add_mesh(*gc.extract_isosurface(dome, 0.0), kind="salt", name="dome", color=(0.85, 0.85, 0.8))  # glue: segyio
    for fpath in faults:
        scene.add_mesh(trimesh.load_mesh(fpath), kind="fault", color=(0.85, 0.15, 0.1))  # glue: trimesh
    scene.add_mesh(trimesh.load_mesh(well), kind="well", name="well", color=(0.1, 0.3, 0.9))  # glue: trimesh
    return scene


def count_glue() -> dict[str, int]:
    """Lines of build_scene that carry a "glue: <source>" marker, per source."""
    import inspect

    counts: dict[str, int] = {}
    for line in inspect.getsource(build_scene).splitlines():
        if "# glue: " in line:
            src = line.split("# glue: ")[1].split()[0]
            counts[src] = counts.get(src, 0) + 1
    return counts


def main(argv: Sequence[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--out", default="examples/out/geodata")
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--quick", action="store_true", help="a small image (for CI)")
    args = ap.parse_args(argv)
    w, h = (240, 180) if args.quick else (args.width, args.height)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        scene = build_scene(*write_data(Path(tmp)))
    bounds = scene.bounds
    assert bounds is not None
    (x0, y0, z0), (x1, y1, z1) = bounds
    c = np.array([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2])
    span = max(x1 - x0, y1 - y0)
    cam = gc.Camera.look_at(c + (-0.8 * span, -1.3 * span, 0.2 * span), c, fov_y=40.0, z_scale=2.0)
    r = gc.Renderer(w, h)
    res = r.render(scene, cam, culling="horizon")
    ref = r.render(scene, cam, culling="none")
    assert np.array_equal(res.image, ref.image), "horizon culling must give the unculled image"
    res.save_png(str(out / "scene.png"))
    kinds = [scene.object_info(i)["kind"] for i in scene.object_ids()]
    print(f"{scene}: {', '.join(f'{kinds.count(k)} {k}' for k in dict.fromkeys(kinds))}")
    print(f"bounds {bounds}")
    print(f"horizon culling drew {res.stats['tiles_drawn']}/{res.stats['tiles_total']} tiles "
          f"({res.stats['triangles_drawn']} of {res.stats['triangles_fine_total']} triangles)")
    print("glue lines per source:", count_glue())
    print(f"wrote {out / 'scene.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

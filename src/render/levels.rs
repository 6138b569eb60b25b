//! Stage 2b of a frame: the level of detail of every tile ([`choose_levels`]), and the frame's
//! stats per level (triangles drawn, grids' cells and faces).

use super::{GridLod, Lod, RenderOutput, Renderer, MAX_SHADING_LEVELS, MAX_TUBE_SHADING_LEVELS};
use crate::camera::{Camera, FrameCamera};
use crate::cull::Stat;
use crate::gpu::{DrawArgs, SceneGeometry};
use crate::lod::levels::exaggerated;
use crate::scene::Scene;
use glam::DVec3;

/// Names of the per-level triangle counts in the stats (`triangles_level{l}`).
const LEVEL_STATS: [&str; 1 + crate::lod::levels::MAX_LEVELS] = [
    "triangles_level0",
    "triangles_level1",
    "triangles_level2",
    "triangles_level3",
    "triangles_level4",
    "triangles_level5",
];

/// Per tile: the level chosen (0 = fine) and its error in pixels.
pub(super) type ChosenLevels = (Vec<u8>, Vec<f32>);

/// Stage 2b: the level of detail of every tile for this frame, and with `Lod::ScreenError` each
/// tile's chosen level and its error in pixels. The error of a level (world units) is exaggerated
/// where that enlarges it ([`exaggerated`](crate::lod::levels::exaggerated): only its vertical part stretches) and projected at the
/// tile box's nearest point (perspective) or with the orthographic scale; a box that contains the
/// eye gets level 0. Cheap on the CPU (one pass over the tiles), so it runs there, before the
/// strategy, with no read-back.
#[allow(clippy::too_many_arguments)]
pub(super) fn choose_levels(
    g: &SceneGeometry,
    scene: &Scene,
    camera: &Camera,
    fc: &FrameCamera,
    dist2: &[f64],
    height: u32,
    (lod, grid_lod): (Lod, GridLod),
    origin: DVec3,
) -> (Vec<DrawArgs>, Option<ChosenLevels>) {
    // Per tile: the grid block's leaf cell size, None for tiles of other objects.
    let mut grid_cell: Vec<Option<(f64, f64)>> = Vec::with_capacity(g.n_tiles());
    for o in scene.objects() {
        match o.grid() {
            Some(info) => grid_cell.extend(info.cell_size.iter().map(|&c| Some(c))),
            None => grid_cell.extend(std::iter::repeat_n(None, o.tiles.len())),
        }
    }
    let any_grid = grid_cell.iter().any(|c| c.is_some());
    if lod == Lod::Full && (grid_lod == GridLod::Full || !any_grid) {
        return (g.fine.clone(), None);
    }
    let proj = fc.view_proj * fc.view.inverse();
    let px_per_unit = proj.y_axis.y.abs() * height as f64 / 2.0;
    let perspective = fc.projection == crate::camera::Projection::Perspective;
    let zv = DVec3::new(1.0, 1.0, camera.z_scale);
    let objects = scene.objects();
    // Per object, 8-bit colour levels per unit of shading error (unexaggerated), and whether it is
    // a well tube (see `turn` below).
    let shade_levels: Vec<(f64, bool)> = objects
        .iter()
        .map(|o| {
            let tube = o.tiles.iter().any(|t| !t.ring_z.is_empty());
            (crate::lod::shading::shade_levels_per_chord(o.max_color_channel() as f64, 1.0), tube)
        })
        .collect();
    // How much exaggeration may multiply a level's shading error: normals turn by up to
    // max(z_scale, 1 / z_scale). A tube's rings are not exaggerated where z_scale > 1 (draw.wgsl
    // `drawn_normal`); its shading error is the turn of its normals plus its displacement (at most
    // its error) over its radius (`lod::tube`), and exaggeration lengthens that displacement by
    // `exaggerated(error) / error` at most.
    let turn = |lv: &crate::gpu::geometry::LevelDraw, tube: bool| {
        let z = camera.z_scale;
        if tube && z > 1.0 && lv.error > 0.0 {
            exaggerated(lv.error, lv.error_z, z) / lv.error as f64
        } else if z > 0.0 {
            z.max(1.0 / z)
        } else {
            1.0
        }
    };
    let mut args = Vec::with_capacity(g.n_tiles());
    let (mut level, mut err_px) = (Vec::with_capacity(g.n_tiles()), Vec::with_capacity(g.n_tiles()));
    let mut scales = Vec::with_capacity(g.n_tiles());
    // (Only height-field tiles are ever too deep: `SceneGeometry::too_deep`.)
    let fields = g.height_blocks.iter().any(Option::is_some);
    let clearance = (lod != Lod::Full && fields).then(|| g.clearances(scene));
    for (i, &d2) in dist2.iter().enumerate() {
        let scale = if perspective {
            if d2 > 0.0 {
                px_per_unit / d2.sqrt()
            } else {
                f64::INFINITY
            }
        } else {
            px_per_unit
        };
        scales.push(scale);
        let px_of = |l: &crate::gpu::geometry::LevelDraw| {
            let e = exaggerated(l.error, l.error_z, camera.z_scale);
            if e == 0.0 {
                0.0
            } else {
                e * scale
            }
        };
        let (per_chord, tube) = shade_levels[g.tile_object_cpu[i] as usize];
        // The coarsest level within `max_px` pixels of error and MAX_SHADING_LEVELS of colour.
        let screen = |max_px: f64| {
            let mut l = 0usize;
            for (k, lv) in g.levels[i].iter().enumerate() {
                let most = if tube { MAX_TUBE_SHADING_LEVELS } else { MAX_SHADING_LEVELS };
                if px_of(lv) > max_px || lv.shading_error as f64 * per_chord * turn(lv, tube) > most {
                    break;
                }
                if clearance.as_ref().is_some_and(|c| g.too_deep(i, k + 1, lv.error_z, c)) {
                    break;
                }
                l = k + 1;
            }
            l
        };
        let l = match (grid_cell.get(i).copied().flatten(), grid_lod, lod) {
            (Some(_), GridLod::Full, _) | (None, _, Lod::Full) => 0,
            (Some(cell), GridLod::Distance { alpha, lambda }, _) => {
                let (lo, hi) = g.bbox[i];
                let off = objects[g.tile_object_cpu[i] as usize].placement(origin);
                let centre = ((lo + hi) * 0.5 + off) * zv;
                let d = (centre - fc.eye).length();
                crate::grid::distance_level(d, cell, alpha, lambda, g.levels[i].len())
            }
            (Some(_), GridLod::ScreenError { max_pixel_error }, _) => screen(max_pixel_error),
            (None, _, Lod::ScreenError { max_pixel_error }) => screen(max_pixel_error),
        };
        let (a, e) =
            if l == 0 { (g.fine[i], 0.0) } else { (g.levels[i][l - 1].args, px_of(&g.levels[i][l - 1]) as f32) };
        args.push(a);
        level.push(l as u8);
        err_px.push(e);
    }
    if let Lod::ScreenError { max_pixel_error } = lod {
        let budget = super::groups::Budget { scale: &scales, z_scale: camera.z_scale, max_px: max_pixel_error };
        super::groups::group_levels(g, scene, &budget, (&level, &mut args, &mut err_px));
    }
    (args, Some((level, err_px)))
}

impl Renderer {
    /// LOD stats of a frame: triangles drawn per level, the largest error used (pixels, metres),
    /// the tiles drawn with sides shared coarse (`tiles_grouped`). `draw_args`: the frame's draws, one per tile.
    pub(super) fn lod_stats(&self, out: &mut RenderOutput, level: &[u8], err_px: &[f32], draw_args: &[DrawArgs]) {
        let g = self.geometry.as_ref().expect("uploaded");
        let mut tris = [0u64; LEVEL_STATS.len()];
        let (mut max_px, mut max_m, mut grouped) = (0.0f64, 0.0f64, 0u64);
        for (i, &drawn) in out.tile_drawn.iter().enumerate() {
            if !drawn {
                continue;
            }
            let l = level[i] as usize;
            let (args, err) = match (l, draw_args.get(i)) {
                (0, _) => (g.fine[i], 0.0),
                // A variant with shared coarse sides (`render::groups`), with its group error.
                (_, Some(d)) if g.is_variant(i, l, d) => {
                    grouped += 1;
                    (*d, g.levels[i][l - 1].grouped_error)
                }
                _ => (g.levels[i][l - 1].args, g.levels[i][l - 1].error),
            };
            tris[l] += args.index_count as u64 / 3;
            max_px = max_px.max(err_px[i] as f64);
            max_m = max_m.max(err as f64);
        }
        for (name, t) in LEVEL_STATS.iter().zip(tris) {
            out.stats.extra.push((name, Stat::Count(t)));
        }
        out.stats.extra.push(("tiles_grouped", Stat::Count(grouped)));
        out.stats.extra.push(("lod_max_error_px", Stat::Float(max_px)));
        out.stats.extra.push(("lod_max_error_m", Stat::Float(max_m)));
    }
}

/// Names of the per-level cell and face counts of grids (`grid_cells_level{l}`, `grid_faces_level{l}`).
const GRID_STATS: [[&str; 2]; 1 + crate::lod::levels::MAX_LEVELS] = [
    ["grid_cells_level0", "grid_faces_level0"],
    ["grid_cells_level1", "grid_faces_level1"],
    ["grid_cells_level2", "grid_faces_level2"],
    ["grid_cells_level3", "grid_faces_level3"],
    ["grid_cells_level4", "grid_faces_level4"],
    ["grid_cells_level5", "grid_faces_level5"],
];

/// Grids' merged cells and faces drawn per level, over the drawn blocks (only when the scene has
/// a grid), and `grid_interior_triangles_skipped`: the interior triangles of drawn blocks left out
/// (`interior`: indices per tile). `level`: each tile's level (None = all 0).
pub(super) fn grid_stats(scene: &Scene, out: &mut RenderOutput, level: Option<&[u8]>, interior: &[u32]) {
    let mut sums = [[0u64; 2]; GRID_STATS.len()];
    let skipped: u64 =
        (interior.iter().zip(&out.tile_drawn).filter(|(_, &d)| d).map(|(&n, _)| n as u64).sum::<u64>()) / 3;
    let (mut any, mut t) = (false, 0usize);
    for o in scene.objects() {
        let Some(info) = o.grid() else {
            t += o.tiles.len();
            continue;
        };
        any = true;
        for b in &info.block_levels {
            if out.tile_drawn.get(t).copied().unwrap_or(false) {
                let l = level.and_then(|l| l.get(t)).map_or(0, |&l| l as usize).min(GRID_STATS.len() - 1);
                if let Some(s) = b.get(l.min(b.len().saturating_sub(1))) {
                    sums[l][0] += s.cells;
                    sums[l][1] += s.faces;
                }
            }
            t += 1;
        }
    }
    if any {
        for (names, v) in GRID_STATS.iter().zip(sums) {
            out.stats.extra.push((names[0], Stat::Count(v[0])));
            out.stats.extra.push((names[1], Stat::Count(v[1])));
        }
        out.stats.extra.push(("grid_interior_triangles_skipped", Stat::Count(skipped)));
    }
}

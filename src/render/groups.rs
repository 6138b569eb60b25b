//! Stage 2c of a frame: height-field tiles whose neighbours are drawn at the same level share
//! those sides at the level's stride (`lod::groups`) instead of drawing them at full resolution.

use crate::gpu::geometry::NO_VARIANTS;
use crate::gpu::{DrawArgs, SceneGeometry};
use crate::lod::levels::exaggerated;
use crate::scene::Scene;

/// What [`group_levels`] decides with: per tile, pixels per world unit at its box's nearest point
/// (`scale`), the exaggeration, and the largest error allowed on screen (pixels).
pub(super) struct Budget<'a> {
    pub scale: &'a [f64],
    pub z_scale: f64,
    pub max_px: f64,
}

/// Turns this frame's choice (`level`, `args`, `err_px`, one per tile, as
/// `levels::choose_levels` made it) into variants with shared sides: per height field,
/// `lod::groups::stitch` over the tiles that may draw one — a non-empty tile at a level with
/// variants whose group error stays within the budget and below the tile's clearance
/// (`lod::clearance`: a tile so drawn never writes the fine depth, `SceneGeometry::frame_runs`,
/// whose search along the pixel's ray stays within the tile's own samples, where a coarse shared
/// side parts from the fine surface) — and each such tile with a non-empty mask draws that
/// variant, its error the group error. Levels are not changed, so a tile draws no more
/// triangles than before; a side is coarse on both of its tiles or on neither (no crack).
pub(super) fn group_levels(
    g: &SceneGeometry,
    scene: &Scene,
    budget: &Budget<'_>,
    (level, args, err_px): (&[u8], &mut [DrawArgs], &mut [f32]),
) {
    let mut clearance = None; // measured on first use (cached per placement)
    let mut first = 0;
    for o in scene.objects() {
        let range = first..first + o.tiles.len();
        first = range.end;
        let has_variants = |k: usize| g.levels[k].iter().any(|l| l.grouped != NO_VARIANTS);
        if !range.clone().any(has_variants) {
            continue;
        }
        let clearance = clearance.get_or_insert_with(|| g.clearances(scene));
        let tx = o.tiles.iter().map(|t| t.ix as usize + 1).max().unwrap_or(0);
        let ty = o.tiles.iter().map(|t| t.iy as usize + 1).max().unwrap_or(0);
        let mut slot = vec![None; tx * ty];
        let mut may = vec![None; tx * ty];
        for (k, t) in range.clone().zip(&o.tiles) {
            let s = t.iy as usize * tx + t.ix as usize;
            slot[s] = Some(k);
            let m = level[k];
            let Some(lv) = (m > 0).then(|| &g.levels[k][m as usize - 1]) else { continue };
            let ok = g.fine[k].index_count > 0
                && lv.grouped != NO_VARIANTS
                && px(budget, k, lv.grouped_error) <= budget.max_px
                && lv.grouped_error < clearance[k];
            may[s] = ok.then_some(m);
        }
        let masks = crate::lod::groups::stitch(tx, ty, &may);
        for (s, &mask) in masks.iter().enumerate() {
            let (Some(k), true) = (slot[s], mask != 0) else { continue };
            let m = level[k] as usize;
            let v = g.variant(k, m, mask).expect("a tile that may stitch has variants");
            (args[k], err_px[k]) = (v, px(budget, k, g.levels[k][m - 1].grouped_error) as f32);
        }
    }
}

/// A vertical error `e` (world units) of tile `k` on screen, exaggerated, in pixels.
fn px(b: &Budget<'_>, k: usize, e: f32) -> f64 {
    if e == 0.0 {
        return 0.0;
    }
    exaggerated(e, e, b.z_scale) * b.scale[k]
}

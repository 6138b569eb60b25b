//! Stage 2c of a frame: height-field tiles drawn in groups (`lod::groups`), where a group of
//! 2^d × 2^d tiles at one level costs fewer triangles than its tiles each with a full-resolution
//! border.

use crate::gpu::{DrawArgs, SceneGeometry};
use crate::lod::groups::MAX_GROUP_DEPTH;
use crate::lod::levels::exaggerated;
use crate::scene::Scene;

/// What [`group_levels`] decides with: per tile, pixels per world unit at its box's nearest point
/// (`scale`), the exaggeration, and the largest error allowed on screen (pixels).
pub(super) struct Budget<'a> {
    pub scale: &'a [f64],
    pub z_scale: f64,
    pub max_px: f64,
}

/// Regroups this frame's choice (`level`, `args`, `err_px`, one per tile, as
/// `levels::choose_levels` made it): bottom-up over depths d = 1..=[`MAX_GROUP_DEPTH`], every
/// aligned block of 2^d × 2^d tiles of one height field whose non-empty tiles all have group draws
/// is drawn as a group at the finest level among its tiles' current ones, where that level's group
/// error stays within the budget on every tile and the group's triangles are fewer than its tiles'
/// current ones (which may already be groups of depth d - 1), and below every tile's clearance
/// (`lod::clearance`): a grouped tile never writes the fine depth (`SceneGeometry::frame_runs`),
/// whose search along the pixel's ray stays within the tile's own samples, where a coarse shared
/// side parts from the fine surface. A group's tiles then share their
/// inner sides at that level's stride (no crack) and keep its outline at full resolution (none
/// with whatever lies beyond). Tiles without triangles take part in any group (they draw
/// nothing); a tile with holes (no group draws) keeps every group it lies in from forming.
pub(super) fn group_levels(
    g: &SceneGeometry,
    scene: &Scene,
    budget: &Budget<'_>,
    (level, args, err_px): (&mut [u8], &mut [DrawArgs], &mut [f32]),
) {
    let mut clearance = None; // measured on first use (cached per placement)
    let mut first = 0;
    for o in scene.objects() {
        let range = first..first + o.tiles.len();
        first = range.end;
        let has_groups = |k: usize| g.levels[k].iter().any(|l| l.grouped[0].index_count > 0);
        if !range.clone().any(has_groups) {
            continue;
        }
        let clearance = clearance.get_or_insert_with(|| g.clearances(scene));
        let tx = o.tiles.iter().map(|t| t.ix as usize + 1).max().unwrap_or(0);
        let ty = o.tiles.iter().map(|t| t.iy as usize + 1).max().unwrap_or(0);
        let mut slot = vec![None; tx * ty];
        for (k, t) in range.clone().zip(&o.tiles) {
            slot[t.iy as usize * tx + t.ix as usize] = Some(k);
        }
        let mut cost: Vec<u64> = range.clone().map(|k| args[k].index_count as u64 / 3).collect();
        for d in 1..=MAX_GROUP_DEPTH {
            let side = 1usize << d;
            if side / 2 >= tx.max(ty) {
                break; // the last depth's groups held the whole object
            }
            for gy in 0..ty.div_ceil(side) {
                for gx in 0..tx.div_ceil(side) {
                    let members: Vec<usize> = (gy * side..((gy + 1) * side).min(ty))
                        .flat_map(|iy| (gx * side..((gx + 1) * side).min(tx)).map(move |ix| iy * tx + ix))
                        .filter_map(|s| slot[s])
                        .filter(|&k| g.fine[k].index_count > 0)
                        .collect();
                    let Some(m) = members.iter().map(|&k| level[k]).min().filter(|&m| m > 0) else { continue };
                    let (mut merged, mut now) = (0u64, 0u64);
                    let fits = members.iter().all(|&k| {
                        let Some(lv) = g.levels[k].get(m as usize - 1) else { return false };
                        let a = lv.grouped[d - 1];
                        merged += a.index_count as u64 / 3;
                        now += cost[k - range.start];
                        a.index_count > 0
                            && px(budget, k, lv.grouped_error) <= budget.max_px
                            && lv.grouped_error < clearance[k]
                    });
                    if !fits || merged >= now {
                        continue;
                    }
                    for &k in &members {
                        let lv = &g.levels[k][m as usize - 1];
                        (level[k], args[k], err_px[k]) = (m, lv.grouped[d - 1], px(budget, k, lv.grouped_error) as f32);
                        cost[k - range.start] = args[k].index_count as u64 / 3;
                    }
                }
            }
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

//! `culling="horizon"`: the strategy around [`HorizonTree`]: one quadtree per height field and
//! z_scale, culled on the CPU for each frame; meshes are drawn unculled. Stats: `nodes_visited`,
//! `nodes_culled` (all height fields together), `fields_unculled` (height fields whose trees the
//! view left unculled, every tile visible: the validity rule in the module above, e.g. a view
//! within 30° of vertical), `trees_built` (this frame), `cache_bytes` (the tree cache after this
//! frame); array `horizon`: the final horizon of the first height field.
//!
//! # The tree cache
//!
//! A tree costs about 4.5 bytes per sample and tens of milliseconds per million samples to build
//! (1000 × 1000 samples: 4.5 MB; that frame culls in ~60 ms, a cached one in ~15 ms), so trees are
//! cached between frames, keyed by (scene geometry key, object id, z_scale). Trees are built in
//! object-local coordinates (origin-relative, exaggerated, *without* the object's offset) and the
//! offset is applied at cull time through the view-projection ([`HorizonTree::cull_translated`]),
//! so `Scene::translate` never rebuilds a tree. The cache is bounded by a byte budget
//! ([`DEFAULT_CACHE_BUDGET`] unless `Renderer::set_cache_budget` says otherwise): after each frame the least recently
//! used trees are dropped until it fits (a frame whose trees alone exceed the budget rebuilds them
//! next time). Trees of an older geometry of the same scene can never be used again and are
//! dropped at once; trees of other scenes stay until the budget evicts them.
//!
//! Rotated height fields: the tree is built in the grid's own frame (axis-aligned, `dy < 0` for a
//! yflipped grid, which the tree handles), and the rotation about sample (0, 0) is folded into the
//! matrix it culls with together with the offset (`view_proj * T(offset) * R`, see
//! [`HorizonTree::cull_in_frame`]). Unrotated, untranslated fields use the identity frame, i.e.
//! exactly the plain `cull`.

use super::{HeightGrid, HorizonTree};

use crate::cull::{CullStrategy, Draw, FrameInputs, Pixels, Stat, Visible, DEFAULT_CACHE_BUDGET};
use crate::error::Result;
use crate::lod::cos_sin_deg;
use crate::scene::HeightfieldInfo;
use glam::{DMat4, DVec3, DVec4};

/// Tree cache key: (scene uid, the object's geometry stamp, z_scale bits): a tree stays valid
/// while its height field does, whatever happens to the scene's other objects (a moved slice).
type TreeKey = (u64, u64, u64);

struct Cached {
    key: TreeKey,
    tree: HorizonTree,
    bytes: u64,
    /// The frame that last used it (for LRU).
    used: u64,
}

pub struct Horizon {
    trees: Vec<Cached>,
    budget: u64,
    frame: u64,
}

impl Default for Horizon {
    fn default() -> Self {
        Self { trees: Vec::new(), budget: DEFAULT_CACHE_BUDGET, frame: 0 }
    }
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Horizon::default())
}

impl Horizon {
    /// Bytes of trees held.
    pub fn cache_bytes(&self) -> u64 {
        self.trees.iter().map(|c| c.bytes).sum()
    }

    /// Drops least recently used trees until the cache fits the budget.
    fn evict(&mut self) {
        let mut total = self.cache_bytes();
        while total > self.budget {
            let Some(i) = (0..self.trees.len()).min_by_key(|&i| self.trees[i].used) else { break };
            total -= self.trees.swap_remove(i).bytes;
        }
    }
}

impl CullStrategy for Horizon {
    fn name(&self) -> &'static str {
        "horizon"
    }

    fn set_cache_budget(&mut self, bytes: u64) {
        self.budget = bytes;
        self.evict();
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, _enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        self.frame += 1;
        let zs = f.camera.z_scale;
        let uid = f.scene.geometry_key().0;
        // A geometry this scene no longer holds cannot come back (stamps are never reused).
        let live: std::collections::HashSet<u64> = f.scene.objects().iter().map(|o| o.geometry_stamp).collect();
        self.trees.retain(|c| c.key.0 != uid || live.contains(&c.key.1));
        let mut mask = Vec::with_capacity(f.n_tiles());
        let (mut visited, mut culled, mut built, mut unculled, mut horizon) = (0u32, 0u32, 0u64, 0u64, None);
        for o in f.scene.objects() {
            let Some(hf) = o.heightfield() else {
                mask.extend(std::iter::repeat_n(true, o.tiles.len()));
                continue;
            };
            let HeightfieldInfo { nx, ny, x0, y0, dx, dy, rotation, tiles, .. } = hf;
            let tk: TreeKey = (uid, o.geometry_stamp, zs.to_bits());
            let idx = match self.trees.iter().position(|c| c.key == tk) {
                Some(i) => i,
                None => {
                    let z = o.height_grid().unwrap_or_default();
                    let zr: Vec<f32> = z.iter().map(|&v| (v as f64 * zs) as f32).collect();
                    let grid =
                        HeightGrid { z: &zr, nx: *nx, ny: *ny, x0: *x0, y0: *y0, dx: *dx, dy: *dy, tiles: *tiles };
                    let tree = HorizonTree::build(&grid);
                    let bytes = tree.bytes() as u64;
                    self.trees.push(Cached { key: tk, tree, bytes, used: 0 });
                    built += 1;
                    self.trees.len() - 1
                }
            };
            let c = &mut self.trees[idx];
            c.used = self.frame;
            // Tree (object-local, grid frame) -> render space: the rotation about sample (0, 0),
            // then the object's offset (exaggerated like the positions).
            let p = o.placement(f.origin);
            let offset = DVec3::new(p.x, p.y, p.z * zs);
            let (cs, sn) = cos_sin_deg(*rotation);
            let frame = if (cs, sn) == (1.0, 0.0) {
                DMat4::from_translation(offset)
            } else {
                let pivot = DVec3::new(*x0, *y0, 0.0);
                let rot =
                    DMat4::from_cols(DVec4::new(cs, sn, 0.0, 0.0), DVec4::new(-sn, cs, 0.0, 0.0), DVec4::Z, DVec4::W);
                DMat4::from_translation(offset + pivot) * rot * DMat4::from_translation(-pivot)
            };
            let r = c.tree.cull_in_frame(f.fc.view_proj, frame, f.fc.eye, f.width, f.height);
            visited += r.nodes_visited;
            culled += r.nodes_culled;
            unculled += u64::from(!r.culling_applied);
            mask.extend_from_slice(&r.tile_visible);
            if horizon.is_none() {
                horizon = Some(r.horizon);
            }
        }
        self.evict();
        let mut v = Visible::new(Draw::Mask(mask), Pixels::FinalImage);
        v.stats = vec![
            ("nodes_visited", Stat::Count(visited as u64)),
            ("nodes_culled", Stat::Count(culled as u64)),
            ("fields_unculled", Stat::Count(unculled)),
            ("trees_built", Stat::Count(built)),
            ("cache_bytes", Stat::Count(self.cache_bytes())),
        ];
        v.arrays.extend(horizon.map(|h| ("horizon", h)));
        Ok(v)
    }
}

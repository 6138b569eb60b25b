//! `culling="horizon"`: the strategy around [`HorizonTree`]: one quadtree per height field
//! (built on first use and cached per geometry, object, z_scale and offset), culled on the CPU
//! for each frame; meshes are drawn unculled. Stats: `nodes_visited`, `nodes_culled` (all height
//! fields together); array `horizon`: the final horizon of the first height field.
//!
//! Rotated height fields: the tree is built in the grid's own frame (axis-aligned, translated like
//! render space: sample (0, 0) at its render-space position, `dy < 0` for a yflipped grid, which the
//! tree handles), and the rotation about sample (0, 0) is folded into the matrix it culls with
//! (`view_proj * frame`, see [`HorizonTree::cull_in_frame`]), as the translation is folded into the
//! grid's origin. Unrotated fields use the identity frame, i.e. exactly the plain `cull`.

use super::{HeightGrid, HorizonTree};
use crate::cull::{CullStrategy, Draw, FrameInputs, Pixels, Stat, Visible};
use crate::error::Result;
use crate::lod::cos_sin_deg;
use crate::scene::ObjectKind;
use glam::{DMat4, DVec3, DVec4};

/// Tree cache key: (scene geometry key, object id, z_scale bits, offset bits).
type TreeKey = ((u64, u64), u32, u64, [u64; 3]);

#[derive(Default)]
pub struct Horizon {
    trees: Vec<(TreeKey, HorizonTree)>,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Horizon::default())
}

impl CullStrategy for Horizon {
    fn name(&self) -> &'static str {
        "horizon"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, _enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let zs = f.camera.z_scale;
        let key = f.scene.geometry_key();
        self.trees.retain(|(k, _)| k.0 == key);
        let mut mask = Vec::with_capacity(f.n_tiles());
        let (mut visited, mut culled, mut horizon) = (0u32, 0u32, None);
        for o in f.scene.objects() {
            let ObjectKind::Heightfield { nx, ny, x0, y0, dx, dy, rotation, tiles } = &o.kind else {
                mask.extend(std::iter::repeat_n(true, o.tiles.len()));
                continue;
            };
            let tk: TreeKey = (key, o.id, zs.to_bits(), o.offset.to_array().map(f64::to_bits));
            let idx = match self.trees.iter().position(|(k, _)| *k == tk) {
                Some(i) => i,
                None => {
                    let z = o.height_grid().unwrap_or_default();
                    let zr: Vec<f32> = z.iter().map(|&v| ((v as f64 + o.offset.z) * zs) as f32).collect();
                    let grid = HeightGrid {
                        z: &zr,
                        nx: *nx,
                        ny: *ny,
                        x0: x0 + o.offset.x,
                        y0: y0 + o.offset.y,
                        dx: *dx,
                        dy: *dy,
                        tiles: *tiles,
                    };
                    self.trees.push((tk, HorizonTree::build(&grid)));
                    self.trees.len() - 1
                }
            };
            // Grid frame -> render space: the rotation about sample (0, 0) (render-space x, y).
            let pivot = DVec3::new(x0 + o.offset.x, y0 + o.offset.y, 0.0);
            let (c, s) = cos_sin_deg(*rotation);
            let frame = if (c, s) == (1.0, 0.0) {
                DMat4::IDENTITY
            } else {
                let rot = DMat4::from_cols(DVec4::new(c, s, 0.0, 0.0), DVec4::new(-s, c, 0.0, 0.0), DVec4::Z, DVec4::W);
                DMat4::from_translation(pivot) * rot * DMat4::from_translation(-pivot)
            };
            let r = self.trees[idx].1.cull_in_frame(f.fc.view_proj, frame, f.fc.eye, f.width, f.height);
            visited += r.nodes_visited;
            culled += r.nodes_culled;
            mask.extend_from_slice(&r.tile_visible);
            if horizon.is_none() {
                horizon = Some(r.horizon);
            }
        }
        let mut v = Visible::new(Draw::Mask(mask), Pixels::FinalImage);
        v.stats = vec![("nodes_visited", Stat::Count(visited as u64)), ("nodes_culled", Stat::Count(culled as u64))];
        v.arrays.extend(horizon.map(|h| ("horizon", h)));
        Ok(v)
    }
}

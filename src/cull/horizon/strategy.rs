//! `culling="horizon"`: the strategy around [`HorizonTree`]: one quadtree per height field
//! (built on first use and cached per geometry, object, z_scale and offset), culled on the CPU
//! for each frame; meshes are drawn unculled. Stats: `nodes_visited`, `nodes_culled` (all height
//! fields together); array `horizon`: the final horizon of the first height field.

use super::{HeightGrid, HorizonTree};
use crate::cull::{CullStrategy, Draw, FrameInputs, Pixels, Stat, Visible};
use crate::error::Result;
use crate::scene::ObjectKind;

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
            let ObjectKind::Heightfield { nx, ny, x0, y0, dx, dy, tiles } = &o.kind else {
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
            let r = self.trees[idx].1.cull(f.fc.view_proj, f.fc.eye, f.width, f.height);
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

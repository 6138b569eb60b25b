//! `culling="frustum"`: CPU view-frustum culling of the tiles' boxes. A tile is not drawn when
//! all eight corners of its box (object offset and exaggeration applied) lie outside one of the
//! six clip planes (`-w ≤ x ≤ w`, `-w ≤ y ≤ w`, `0 ≤ z ≤ w`, wgpu's clip volume, valid for the
//! reverse-Z and the finite and infinite projections the camera builds).
//!
//! Exact: every triangle of a tile lies inside its box, so a box wholly outside one plane has no
//! fragment on screen. The test is done in f64 with a relative margin of 1e-4 of the corner's
//! clip coordinates, far above the f32 round-off of the GPU's own transform, so a box that
//! touches the frustum is always kept. Occlusion is not considered (the occlusion strategies do
//! that). Stat: `tiles_outside`, the tiles culled.

use super::{CullStrategy, Draw, FrameInputs, Pixels, Stat, Visible};
use crate::error::Result;
use glam::{DMat4, DVec3, DVec4};

pub struct Frustum;

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Frustum)
}

/// Relative margin of the plane tests (see the module docs).
const MARGIN: f64 = 1e-4;

/// True when the box `lo..hi` (render space) lies wholly outside one clip plane of `view_proj`.
pub fn box_outside(view_proj: &DMat4, lo: DVec3, hi: DVec3) -> bool {
    let corners: [DVec4; 8] = std::array::from_fn(|i| {
        let p = DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        *view_proj * p.extend(1.0)
    });
    // Signed distances outside each plane; a corner is outside when it exceeds its margin.
    let planes: [fn(DVec4) -> f64; 6] =
        [|c| c.x - c.w, |c| -c.x - c.w, |c| c.y - c.w, |c| -c.y - c.w, |c| c.z - c.w, |c| -c.z];
    planes.iter().any(|plane| {
        corners.iter().all(|c| {
            let m = MARGIN * (c.x.abs() + c.y.abs() + c.z.abs() + c.w.abs());
            plane(*c) > m
        })
    })
}

impl CullStrategy for Frustum {
    fn name(&self) -> &'static str {
        "frustum"
    }

    fn visible_set(&mut self, f: &FrameInputs<'_>, _enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let zs = DVec3::new(1.0, 1.0, f.camera.z_scale);
        let objects = f.scene.objects();
        let mask: Vec<bool> = f
            .geometry
            .bbox
            .iter()
            .zip(&f.geometry.tile_object_cpu)
            .map(|((lo, hi), &oi)| {
                let off = objects[oi as usize].placement(f.origin);
                let (a, b) = ((*lo + off) * zs, (*hi + off) * zs);
                !box_outside(&f.fc.view_proj, a.min(b), a.max(b))
            })
            .collect();
        let outside = mask.iter().filter(|&&v| !v).count() as u64;
        let mut v = Visible::new(Draw::Mask(mask), Pixels::FinalImage);
        v.stats.push(("tiles_outside", Stat::Count(outside)));
        Ok(v)
    }
}

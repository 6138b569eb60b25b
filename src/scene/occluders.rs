//! Enclosed occluder boxes of an object (`Object::occluders`, [`Occluders`]): plain world-space boxes that the
//! caller proves lie behind the object's own drawn surface for every eye outside a given box
//! (an isosurface's: `crate::iso::enclosed`). The scene only stores them; `culling = "implicit"`
//! uses them.

use super::Scene;
use crate::error::{ensure, Result};
use crate::lod::{f32_at_least, f32_at_most};
use glam::DVec3;

/// An object's occluder boxes and the box an eye must lie outside of for them to hold.
#[derive(Clone, Debug, PartialEq)]
pub struct Occluders {
    /// `[lo, hi]` relative to the object's origin (rounded inwards to f32), each wholly behind the
    /// object's own surface for any eye outside `bounds`.
    pub boxes: Vec<[[f32; 3]; 2]>,
    /// The box (relative to the object's origin) the eye must lie outside of (for an isosurface,
    /// its surface's bounding box).
    pub bounds: [[f64; 3]; 2],
}

impl Scene {
    /// Sets object `id`'s occluder boxes: `boxes` (world `(lo, hi)`, before the object's offset)
    /// must each lie behind the object's own surface for any eye outside `bounds` (world box):
    /// every ray from such an eye to a point of a box crosses the object's triangles first. The
    /// boxes are stored relative to the object's origin, rounded inwards to f32 (a box that
    /// vanishes is left out). Errors: no such object (`id`); a box or `bounds` not finite or with
    /// `lo > hi` (`boxes`, `bounds`).
    pub fn set_occluders(
        &mut self,
        id: u32,
        boxes: &[([f64; 3], [f64; 3])],
        bounds: ([f64; 3], [f64; 3]),
    ) -> Result<()> {
        let ok =
            |(lo, hi): &([f64; 3], [f64; 3])| (0..3).all(|a| lo[a].is_finite() && hi[a].is_finite() && lo[a] <= hi[a]);
        ensure(ok(&bounds), "bounds", || format!("bounds {bounds:?}: expected finite lo <= hi"))?;
        if let Some(k) = boxes.iter().position(|b| !ok(b)) {
            let b = boxes[k];
            return Err(crate::error::input_err("boxes", format!("boxes[{k}] is {b:?}; expected finite lo <= hi")));
        }
        let o = self.object_mut(id)?;
        let origin = o.origin;
        let rel = |p: [f64; 3]| (DVec3::from_array(p) - origin).to_array();
        let stored: Vec<[[f32; 3]; 2]> = boxes
            .iter()
            .map(|&(lo, hi)| [rel(lo).map(f32_at_least), rel(hi).map(f32_at_most)])
            .filter(|[lo, hi]| (0..3).all(|a| lo[a] < hi[a]))
            .collect();
        let bounds = [rel(bounds.0), rel(bounds.1)];
        o.occluders = Some(std::sync::Arc::new(Occluders { boxes: stored, bounds }));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::AddOptions;

    #[test]
    fn occluders_are_stored_relative_to_the_origin_rounded_inwards_and_checked() {
        let mut s = Scene::new();
        let v = [[1000.0, 2000.0, -500.0], [1010.0, 2000.0, -500.0], [1000.0, 2010.0, -490.0]];
        let id = s.add_mesh(&v, &[[0, 1, 2]], "isosurface", None, AddOptions::new(1.0)).unwrap();
        let b = ([1001.0, 2001.0, -499.0], [1002.1, 2003.0, -498.0]);
        s.set_occluders(id, &[b, ([1.0; 3], [1.0; 3])], (v[0], [1010.0, 2010.0, -490.0])).unwrap();
        let o = &s.objects()[0];
        let occ = o.occluders.as_deref().unwrap();
        assert_eq!(occ.boxes.len(), 1, "the empty box is left out");
        for a in 0..3 {
            assert!(occ.boxes[0][0][a] as f64 + o.origin[a] >= b.0[a]);
            assert!(occ.boxes[0][1][a] as f64 + o.origin[a] <= b.1[a]);
        }
        let bad = s.set_occluders(id, &[([0.0; 3], [f64::NAN; 3])], (v[0], v[1])).unwrap_err();
        assert!(bad.to_string().contains("boxes"), "{bad}");
        let bad = s.set_occluders(id, &[], (v[1], v[0])).unwrap_err();
        assert!(bad.to_string().contains("bounds"), "{bad}");
        assert!(s.set_occluders(id + 1, &[], (v[0], v[1])).unwrap_err().to_string().contains("id"));
    }
}

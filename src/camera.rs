//! An f64 camera. Matrices are built in f64 relative to the scene origin and only then cast to f32,
//! so UTM-sized coordinates keep their precision. Depth is reverse-Z: perspective uses an infinite
//! far plane (depth = near / distance), orthographic a finite one.
//!
//! Vertical exaggeration `z_scale` maps world z to `z * z_scale` for the scene *and* the camera's eye
//! and target, so a camera keeps looking at the same geological point whatever the exaggeration
//! (the same convention as VTK's `SetScale` with the camera placed in scaled coordinates).

mod orbit;
pub use orbit::{Lens, Orbit};

use crate::error::{ensure, input_err, num, Result};
use glam::dcamera::rh::{proj::directx, view::look_at_mat4};
use glam::{DMat4, DVec3};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    Perspective,
    Orthographic,
}

impl Projection {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "perspective" => Ok(Self::Perspective),
            "orthographic" => Ok(Self::Orthographic),
            _ => Err(input_err(
                "projection",
                format!("unknown projection {s:?}; expected \"perspective\" or \"orthographic\""),
            )),
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::Perspective => "perspective",
            Self::Orthographic => "orthographic",
        }
    }
}

/// A look-at camera in world coordinates (metres).
#[derive(Clone, Debug)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    /// Vertical field of view in degrees (perspective; also frames orthographic views by default).
    pub fov_y: f64,
    /// Near / far distance along the view axis; `None` = chosen from the scene bounds.
    pub near: Option<f64>,
    pub far: Option<f64>,
    pub projection: Projection,
    /// Height of the orthographic view volume in world units; `None` = the height a perspective
    /// camera with `fov_y` would see at the target.
    pub ortho_height: Option<f64>,
    pub z_scale: f64,
}

/// The near/far planes and matrices actually used for one frame.
#[derive(Clone, Copy, Debug)]
pub struct FrameCamera {
    /// Render space (origin-relative, exaggerated) to clip space.
    pub view_proj: DMat4,
    pub view: DMat4,
    pub near: f64,
    pub far: f64,
    pub projection: Projection,
    /// Perspective only: true when a finite far plane clips (the caller gave `far`).
    pub finite_far: bool,
    /// Eye in render space.
    pub eye: DVec3,
    /// Unit view direction in render space.
    pub forward: DVec3,
}

/// Smallest near distance accepted (and the floor of the automatic one), world units.
pub const MIN_NEAR: f64 = 1e-6;
/// Smallest vertical field of view accepted, degrees.
pub const MIN_FOV_Y: f64 = 1e-6;
/// Range of vertical exaggeration accepted.
pub const MIN_Z_SCALE: f64 = 1e-6;
pub const MAX_Z_SCALE: f64 = 1e6;
/// Smallest orthographic view height accepted, world units: below it the f32 projection's scale
/// (2 / height) and the f32 positions cannot resolve the view (1e-300 overflowed to an empty image).
pub const MIN_ORTHO_HEIGHT: f64 = 1e-6;
/// Largest near, far and orthographic height accepted, world units (exaggerated): beyond any
/// distance in a scene (coordinates within +-1e12, exaggeration at most 1e6) and far inside f32,
/// whose projection terms overflow or underflow to an empty image near 1e38.
pub const MAX_DISTANCE: f64 = 1e20;
/// Largest coordinate magnitude accepted anywhere (scene and camera), world units: far beyond any
/// geographic coordinate, and small enough that origin-relative f32 positions stay finite.
pub const MAX_COORD: f64 = 1e12;

fn finite3(v: [f64; 3], arg: &str) -> Result<DVec3> {
    for (i, x) in v.iter().enumerate() {
        ensure(x.is_finite(), arg, || format!("component {i} is {x}, expected a finite number"))?;
    }
    Ok(DVec3::from_array(v))
}

impl Camera {
    #[allow(clippy::too_many_arguments)]
    pub fn look_at(
        eye: [f64; 3],
        target: [f64; 3],
        up: [f64; 3],
        fov_y: f64,
        near: Option<f64>,
        far: Option<f64>,
        projection: Projection,
        ortho_height: Option<f64>,
        z_scale: f64,
    ) -> Result<Self> {
        let eye = finite3(eye, "eye")?;
        let target = finite3(target, "target")?;
        let up = finite3(up, "up")?;
        ensure(eye != target, "target", || "target equals eye; the view direction is undefined".into())?;
        ensure(up.try_normalize().is_some(), "up", || format!("up is {up}; expected a non-zero vector"))?;
        ensure(fov_y.is_finite() && fov_y > 0.0 && fov_y < 180.0, "fov_y", || {
            format!("fov_y is {fov_y}; expected degrees in the open interval (0, 180)")
        })?;
        // Below this the f32 projection overflows (focal length > 1e38): an empty image, not a view.
        ensure(fov_y >= MIN_FOV_Y, "fov_y", || {
            format!("fov_y is {}; expected at least {} degrees", num(fov_y), num(MIN_FOV_Y))
        })?;
        ensure(z_scale.is_finite() && z_scale > 0.0, "z_scale", || {
            format!("z_scale is {z_scale}; expected a finite number > 0")
        })?;
        ensure((MIN_Z_SCALE..=MAX_Z_SCALE).contains(&z_scale), "z_scale", || {
            format!(
                "z_scale is {}; expected a vertical exaggeration in [{}, {}]",
                num(z_scale),
                num(MIN_Z_SCALE),
                num(MAX_Z_SCALE)
            )
        })?;
        for (p, arg) in [(eye, "eye"), (target, "target")] {
            for (i, x) in p.to_array().iter().enumerate() {
                ensure(x.abs() <= MAX_COORD, arg, || {
                    format!("component {i} is {}; coordinates must be within +-{MAX_COORD:e}", num(*x))
                })?;
            }
        }
        // The view direction in render space (exaggerated) must be normalisable in f64.
        let dir = (target - eye) * DVec3::new(1.0, 1.0, z_scale);
        ensure(dir.try_normalize().is_some(), "target", || {
            format!("target - eye is {dir} (exaggerated); too short to define a view direction")
        })?;
        if let Some(n) = near {
            ensure(n.is_finite() && n > 0.0, "near", || format!("near is {n}; expected a finite number > 0"))?;
            // Reverse-Z depth is near / distance in f32: a smaller near underflows to "nothing drawn".
            ensure(n >= MIN_NEAR, "near", || format!("near is {}; expected at least {}", num(n), num(MIN_NEAR)))?;
            ensure(n <= MAX_DISTANCE, "near", || {
                format!("near is {}; expected at most {} (world units)", num(n), num(MAX_DISTANCE))
            })?;
        }
        if let Some(f) = far {
            ensure(f.is_finite() && f > 0.0, "far", || format!("far is {f}; expected a finite number > 0"))?;
            ensure(f <= MAX_DISTANCE, "far", || {
                format!("far is {}; expected at most {} (world units)", num(f), num(MAX_DISTANCE))
            })?;
            if let Some(n) = near {
                ensure(f > n, "far", || format!("far ({f}) must be greater than near ({n})"))?;
            }
            // A perspective near plane is never below MIN_NEAR: a far plane at or before twice that
            // could only give an empty image (and a projection with near > far).
            ensure(projection != Projection::Perspective || f > 2.0 * MIN_NEAR, "far", || {
                format!(
                    "far is {}; a perspective camera needs far > {} (its near plane is at least {})",
                    num(f),
                    num(2.0 * MIN_NEAR),
                    num(MIN_NEAR)
                )
            })?;
        }
        if let Some(h) = ortho_height {
            ensure(h.is_finite() && h > 0.0, "ortho_height", || {
                format!("ortho_height is {h}; expected a finite number > 0")
            })?;
            ensure((MIN_ORTHO_HEIGHT..=MAX_DISTANCE).contains(&h), "ortho_height", || {
                format!(
                    "ortho_height is {}; expected a view height in [{}, {}] (world units): other heights \
                     can only give an empty image",
                    num(h),
                    num(MIN_ORTHO_HEIGHT),
                    num(MAX_DISTANCE)
                )
            })?;
        }
        Ok(Self { eye, target, up, fov_y, near, far, projection, ortho_height, z_scale })
    }

    /// Maps a world point to render space: relative to `origin`, z exaggerated.
    pub fn to_render(&self, p: DVec3, origin: DVec3) -> DVec3 {
        let r = p - origin;
        DVec3::new(r.x, r.y, r.z * self.z_scale)
    }

    /// The up vector actually used: `up` unless it is (nearly) parallel to the view direction,
    /// then the world axis least aligned with the view direction (looking straight down works).
    pub fn effective_up(&self, forward: DVec3) -> DVec3 {
        let up = self.up.normalize();
        if forward.cross(up).length() > 1e-9 {
            return up;
        }
        let candidates = [DVec3::Y, DVec3::X, DVec3::Z];
        *candidates.iter().min_by(|a, b| a.dot(forward).abs().total_cmp(&b.dot(forward).abs())).unwrap()
    }

    /// Near/far and matrices for a frame whose visible content (render space) lies in `bounds`.
    pub fn frame(&self, origin: DVec3, bounds: Option<(DVec3, DVec3)>, aspect: f64) -> FrameCamera {
        let eye = self.to_render(self.eye, origin);
        let target = self.to_render(self.target, origin);
        let forward = (target - eye).normalize();
        let up = self.effective_up(forward);
        let view = look_at_mat4(eye, target, up);
        // Distance range of the scene's bounding box along the view axis.
        let (dmin, dmax) = match bounds {
            Some((lo, hi)) => {
                let mut dmin = f64::INFINITY;
                let mut dmax = f64::NEG_INFINITY;
                for i in 0..8 {
                    let c = DVec3::new(
                        if i & 1 == 0 { lo.x } else { hi.x },
                        if i & 2 == 0 { lo.y } else { hi.y },
                        if i & 4 == 0 { lo.z } else { hi.z },
                    );
                    let d = (c - eye).dot(forward);
                    dmin = dmin.min(d);
                    dmax = dmax.max(d);
                }
                (dmin, dmax)
            }
            None => (1.0, (target - eye).length() * 2.0 + 1.0),
        };
        let span = (dmax - dmin).abs().max(1e-6);
        let far = self.far.unwrap_or_else(|| (dmax + 0.01 * span).max(1e-3));
        let (near, far, proj) = match self.projection {
            Projection::Perspective => {
                // Reverse-Z with a float depth buffer keeps relative precision at any distance, so a
                // small near costs nothing; never let it reach zero. The floor is absolute: one tied
                // to `far` (near >= far * 1e-6) clipped nearby geometry whenever the camera was inside
                // a large scene or the caller gave a large `far`.
                let mut near = self.near.unwrap_or_else(|| (dmin - 0.01 * span).max(MIN_NEAR));
                if self.near.is_none() && self.far.is_some() {
                    near = near.min(far * 0.5).max(MIN_NEAR);
                }
                // Without a given far the far plane is at infinity (nothing is clipped behind) and
                // `far` is only reported; a given far clips with a finite reverse-Z projection.
                let fov = self.fov_y.to_radians();
                let p = match self.far {
                    None => directx::perspective_infinite_reverse(fov, aspect, near),
                    // Arguments swapped: near maps to depth 1, far to 0.
                    Some(f) => directx::perspective(fov, aspect, f, near),
                };
                let far = if self.far.is_none() { far.max(near * 1.01) } else { far };
                (near, far, p)
            }
            Projection::Orthographic => {
                let mut near = self.near.unwrap_or_else(|| (dmin - 0.01 * span).max(0.0));
                if self.near.is_none() && self.far.is_some() {
                    near = near.min(far * 0.5);
                }
                // The same far for the projection and for linear_depth (they used to differ here).
                let far = far.max(near * (1.0 + 1e-6) + 1e-3);
                let h = self
                    .ortho_height
                    .unwrap_or_else(|| 2.0 * (target - eye).length() * (self.fov_y.to_radians() * 0.5).tan());
                let w = h * aspect;
                // Reverse-Z: near maps to depth 1, far to 0.
                let p = directx::orthographic(-w / 2.0, w / 2.0, -h / 2.0, h / 2.0, far, near);
                (near, far, p)
            }
        };
        let finite_far = self.far.is_some();
        FrameCamera { view_proj: proj * view, view, near, far, finite_far, projection: self.projection, eye, forward }
    }
}

impl FrameCamera {
    /// Direction towards the head light, over the viewer's shoulder (up and to the right), so
    /// surfaces facing the camera are lit. Render space, unit length.
    pub fn light_dir(&self) -> DVec3 {
        let inv = self.view.inverse();
        let right = inv.transform_vector3(DVec3::X);
        let up = inv.transform_vector3(DVec3::Y);
        (-self.forward + 0.6 * up + 0.3 * right).normalize()
    }

    /// Converts a reverse-Z depth-buffer value to the distance along the view axis (+inf where
    /// nothing was drawn, i.e. the cleared value 0).
    #[inline]
    pub fn linear_depth(&self, d: f32) -> f32 {
        if d <= 0.0 {
            return f32::INFINITY;
        }
        match self.projection {
            Projection::Perspective if self.finite_far => {
                (self.near * self.far / (d as f64 * (self.far - self.near) + self.near)) as f32
            }
            Projection::Perspective => (self.near / d as f64) as f32,
            // near + (1 - d)(far - near), not far - d (far - near): the latter cancels to 0 when
            // far >> near.
            Projection::Orthographic => (self.near + (1.0 - d as f64) * (self.far - self.near)) as f32,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(projection: Projection) -> Camera {
        Camera::look_at([0.0, 0.0, 100.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0], 45.0, None, None, projection, None, 1.0)
            .unwrap()
    }

    #[test]
    fn straight_down_with_z_up_is_handled() {
        let c = cam(Projection::Perspective);
        let f = c.frame(DVec3::ZERO, Some((DVec3::splat(-10.0), DVec3::splat(10.0))), 1.0);
        assert!(f.view_proj.is_finite());
    }

    #[test]
    fn depth_round_trip() {
        for p in [Projection::Perspective, Projection::Orthographic] {
            let c = cam(p);
            let f = c.frame(DVec3::ZERO, Some((DVec3::new(-10.0, -10.0, -5.0), DVec3::new(10.0, 10.0, 5.0))), 1.0);
            for dist in [96.0, 100.0, 104.0] {
                let clip = f.view_proj * glam::DVec4::new(0.0, 0.0, 100.0 - dist, 1.0);
                let d = (clip.z / clip.w) as f32;
                assert!((0.0..=1.0).contains(&d), "{p:?} {d}");
                let back = f.linear_depth(d) as f64;
                assert!((back - dist).abs() / dist < 1e-5, "{p:?} {back} vs {dist}");
            }
        }
    }

    #[test]
    fn given_far_clips_and_round_trips() {
        let c = Camera::look_at(
            [0.0, 0.0, 100.0],
            [0.0; 3],
            [0.0, 0.0, 1.0],
            45.0,
            Some(50.0),
            Some(150.0),
            Projection::Perspective,
            None,
            1.0,
        )
        .unwrap();
        let f = c.frame(DVec3::ZERO, None, 1.0);
        assert!(f.finite_far && f.near == 50.0 && f.far == 150.0);
        let depth_at = |dist: f64| {
            let clip = f.view_proj * glam::DVec4::new(0.0, 0.0, 100.0 - dist, 1.0);
            clip.z / clip.w
        };
        assert!((depth_at(50.0) - 1.0).abs() < 1e-9 && depth_at(150.0).abs() < 1e-9);
        assert!(depth_at(151.0) < 0.0, "beyond far is clipped");
        for dist in [60.0, 100.0, 149.0] {
            let back = f.linear_depth(depth_at(dist) as f32) as f64;
            assert!((back - dist).abs() / dist < 1e-5, "{back} vs {dist}");
        }
    }

    #[test]
    fn bad_arguments_name_themselves() {
        let e =
            Camera::look_at([0.0; 3], [0.0; 3], [0.0, 0.0, 1.0], 45.0, None, None, Projection::Perspective, None, 1.0)
                .unwrap_err();
        assert!(e.to_string().starts_with("target"));
        let e = Camera::look_at(
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            180.0,
            None,
            None,
            Projection::Perspective,
            None,
            1.0,
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("fov_y"));
    }

    #[test]
    fn degenerate_view_sizes_are_errors() {
        let look = |near, far, h| {
            Camera::look_at(
                [0.0, 0.0, 10.0],
                [0.0; 3],
                [0.0, 1.0, 0.0],
                45.0,
                near,
                far,
                Projection::Orthographic,
                h,
                1.0,
            )
        };
        for (near, far, h, arg) in [
            (None, None, Some(1e-300), "ortho_height"),
            (None, None, Some(1e300), "ortho_height"),
            (Some(1e300), None, None, "near"),
            (None, Some(1e300), None, "far"),
        ] {
            let e = look(near, far, h).unwrap_err().to_string();
            assert!(e.starts_with(arg), "{e}");
        }
        assert!(look(None, None, Some(MIN_ORTHO_HEIGHT)).is_ok() && look(None, None, Some(MAX_DISTANCE)).is_ok());
    }
}

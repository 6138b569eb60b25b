//! An f64 camera. Matrices are built in f64 relative to the scene origin and only then cast to f32,
//! so UTM-sized coordinates keep their precision. Depth is reverse-Z: perspective uses an infinite
//! far plane (depth = near / distance), orthographic a finite one.
//!
//! Vertical exaggeration `z_scale` maps world z to `z * z_scale` for the scene *and* the camera's eye
//! and target, so a camera keeps looking at the same geological point whatever the exaggeration
//! (the same convention as VTK's `SetScale` with the camera placed in scaled coordinates).

use crate::error::{ensure, input_err, Result};
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
    /// Eye in render space.
    pub eye: DVec3,
    /// Unit view direction in render space.
    pub forward: DVec3,
}

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
        ensure(up.length() > 0.0, "up", || "up is the zero vector".into())?;
        ensure(fov_y.is_finite() && fov_y > 0.0 && fov_y < 180.0, "fov_y", || {
            format!("fov_y is {fov_y}; expected degrees in the open interval (0, 180)")
        })?;
        ensure(z_scale.is_finite() && z_scale > 0.0, "z_scale", || {
            format!("z_scale is {z_scale}; expected a finite number > 0")
        })?;
        if let Some(n) = near {
            ensure(n.is_finite() && n > 0.0, "near", || format!("near is {n}; expected a finite number > 0"))?;
        }
        if let Some(f) = far {
            ensure(f.is_finite() && f > 0.0, "far", || format!("far is {f}; expected a finite number > 0"))?;
            if let Some(n) = near {
                ensure(f > n, "far", || format!("far ({f}) must be greater than near ({n})"))?;
            }
        }
        if let Some(h) = ortho_height {
            ensure(h.is_finite() && h > 0.0, "ortho_height", || {
                format!("ortho_height is {h}; expected a finite number > 0")
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
        *candidates
            .iter()
            .min_by(|a, b| a.dot(forward).abs().total_cmp(&b.dot(forward).abs()))
            .unwrap()
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
        let (near, proj) = match self.projection {
            Projection::Perspective => {
                // Reverse-Z with a float depth buffer keeps relative precision at any distance, so a
                // small near costs nothing; never let it reach zero.
                let near = self.near.unwrap_or_else(|| (dmin - 0.01 * span).max(far * 1e-6).max(1e-6));
                let p = directx::perspective_infinite_reverse(self.fov_y.to_radians(), aspect, near);
                (near, p)
            }
            Projection::Orthographic => {
                let near = self.near.unwrap_or_else(|| (dmin - 0.01 * span).max(0.0));
                let far = far.max(near + 1e-3);
                let h = self.ortho_height.unwrap_or_else(|| {
                    2.0 * (target - eye).length() * (self.fov_y.to_radians() * 0.5).tan()
                });
                let w = h * aspect;
                // Reverse-Z: near maps to depth 1, far to 0.
                let p = directx::orthographic(-w / 2.0, w / 2.0, -h / 2.0, h / 2.0, far, near);
                (near, p)
            }
        };
        FrameCamera { view_proj: proj * view, view, near, far, projection: self.projection, eye, forward }
    }
}

impl FrameCamera {
    /// Converts a reverse-Z depth-buffer value to the distance along the view axis (+inf where
    /// nothing was drawn, i.e. the cleared value 0).
    #[inline]
    pub fn linear_depth(&self, d: f32) -> f32 {
        if d <= 0.0 {
            return f32::INFINITY;
        }
        match self.projection {
            Projection::Perspective => (self.near / d as f64) as f32,
            Projection::Orthographic => (self.far - d as f64 * (self.far - self.near)) as f32,
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
    fn bad_arguments_name_themselves() {
        let e = Camera::look_at([0.0; 3], [0.0; 3], [0.0, 0.0, 1.0], 45.0, None, None, Projection::Perspective, None, 1.0)
            .unwrap_err();
        assert!(e.to_string().starts_with("target"));
        let e = Camera::look_at([0.0; 3], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0], 180.0, None, None, Projection::Perspective, None, 1.0)
            .unwrap_err();
        assert!(e.to_string().starts_with("fov_y"));
    }
}

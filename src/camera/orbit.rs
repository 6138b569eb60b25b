//! Cameras placed by angles: [`Camera::orbit`] (a target, a compass azimuth, an elevation and a
//! distance), [`Camera::fit`] (the closest view of a box from given angles), and the moves
//! [`Camera::rotated`] and [`Camera::zoomed`].
//!
//! Angles are degrees. `azimuth` is the compass bearing of the eye seen from the target,
//! clockwise from north (+y) seen from above: 0 puts the eye north of the target, 90 east (+x).
//! `elevation` is the eye's angle above the horizontal plane through the target, in [-90, 90]
//! (90 = looking straight down). Everything is laid out in render space (z multiplied by
//! `z_scale`), so angles and distances are those seen in the exaggerated image.

use super::{Camera, Projection};
use crate::error::{ensure, Result};
use glam::DVec3;

/// Where an orbiting eye stands: degrees, degrees, render-space distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub azimuth: f64,
    pub elevation: f64,
    pub distance: f64,
}

/// Every setting of a camera besides its eye and target (`Camera::look_at`'s other arguments).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    pub up: [f64; 3],
    pub fov_y: f64,
    pub near: Option<f64>,
    pub far: Option<f64>,
    pub projection: Projection,
    pub ortho_height: Option<f64>,
    pub z_scale: f64,
}

impl Default for Lens {
    fn default() -> Self {
        Self {
            up: [0.0, 0.0, 1.0],
            fov_y: 45.0,
            near: None,
            far: None,
            projection: Projection::Perspective,
            ortho_height: None,
            z_scale: 1.0,
        }
    }
}

/// Unit vector from the target to the eye.
fn direction(azimuth: f64, elevation: f64) -> DVec3 {
    let (az, el) = (azimuth.to_radians(), elevation.to_radians());
    DVec3::new(az.sin() * el.cos(), az.cos() * el.cos(), el.sin())
}

fn check_angles(azimuth: f64, elevation: f64) -> Result<()> {
    ensure(azimuth.is_finite(), "azimuth", || format!("azimuth is {azimuth}; expected a finite number of degrees"))?;
    ensure((-90.0..=90.0).contains(&elevation), "elevation", || {
        format!("elevation is {elevation}; expected degrees in [-90, 90]")
    })
}

fn check_z_scale(z_scale: f64) -> Result<()> {
    ensure(z_scale.is_finite() && z_scale > 0.0, "z_scale", || {
        format!("z_scale is {z_scale}; expected a finite number > 0")
    })
}

impl Camera {
    /// This camera's settings besides eye and target.
    pub fn lens(&self) -> Lens {
        Lens {
            up: self.up.into(),
            fov_y: self.fov_y,
            near: self.near,
            far: self.far,
            projection: self.projection,
            ortho_height: self.ortho_height,
            z_scale: self.z_scale,
        }
    }

    /// A camera looking at `target` from `o`: in render space the eye is
    /// `target + distance * (sin az cos el, cos az cos el, sin el)`.
    pub fn orbit(target: [f64; 3], o: Orbit, lens: Lens) -> Result<Self> {
        check_angles(o.azimuth, o.elevation)?;
        ensure(o.distance.is_finite() && o.distance > 0.0, "distance", || {
            format!("distance is {}; expected a finite number > 0", o.distance)
        })?;
        check_z_scale(lens.z_scale)?;
        let t = DVec3::from(target);
        let eye = t + o.distance * direction(o.azimuth, o.elevation) / DVec3::new(1.0, 1.0, lens.z_scale);
        let l = lens;
        Camera::look_at(eye.into(), target, l.up, l.fov_y, l.near, l.far, l.projection, l.ortho_height, l.z_scale)
    }

    /// The eye's place about the target, as [`Camera::orbit`] takes it: azimuth in [0, 360) (0
    /// when the eye is straight above or below the target).
    pub fn orbit_angles(&self) -> Orbit {
        let v = (self.eye - self.target) * DVec3::new(1.0, 1.0, self.z_scale);
        let d = v.length();
        let elevation = (v.z / d).clamp(-1.0, 1.0).asin().to_degrees();
        let h = v.x.hypot(v.y);
        let azimuth = if h > 1e-12 * d { v.x.atan2(v.y).to_degrees().rem_euclid(360.0) } else { 0.0 };
        Orbit { azimuth, elevation, distance: d }
    }

    /// Orbited about the target: azimuth + `d_azimuth`, elevation + `d_elevation` clamped to
    /// [-90, 90]; distance and every setting kept.
    pub fn rotated(&self, d_azimuth: f64, d_elevation: f64) -> Result<Self> {
        ensure(d_azimuth.is_finite(), "d_azimuth", || format!("d_azimuth is {d_azimuth}; expected a finite number"))?;
        ensure(d_elevation.is_finite(), "d_elevation", || {
            format!("d_elevation is {d_elevation}; expected a finite number")
        })?;
        let o = self.orbit_angles();
        let o = Orbit {
            azimuth: (o.azimuth + d_azimuth).rem_euclid(360.0),
            elevation: (o.elevation + d_elevation).clamp(-90.0, 90.0),
            ..o
        };
        Camera::orbit(self.target.into(), o, self.lens())
    }

    /// `factor` times the magnification (> 0): a perspective eye moves to distance / factor; an
    /// orthographic view divides its height (`ortho_height`, or what fov_y sees at the target) and
    /// keeps the eye.
    pub fn zoomed(&self, factor: f64) -> Result<Self> {
        ensure(factor.is_finite() && factor > 0.0, "factor", || {
            format!("factor is {factor}; expected a finite number > 0")
        })?;
        let mut o = self.orbit_angles();
        let mut lens = self.lens();
        match self.projection {
            Projection::Perspective => o.distance /= factor,
            Projection::Orthographic => {
                let h = self.ortho_height.unwrap_or_else(|| 2.0 * o.distance * (self.fov_y.to_radians() / 2.0).tan());
                lens.ortho_height = Some(h / factor);
            }
        }
        Camera::orbit(self.target.into(), o, lens)
    }

    /// The camera that looks at the centre of the box `lo..hi` (world, metres) from `azimuth`,
    /// `elevation`, as close as it can stand with all 8 corners inside the view shrunk by
    /// `margin` (in [0, 1): the fraction of the half-width and half-height left free) for images
    /// of width / height `aspect`. Perspective: the smallest such distance; orthographic: the
    /// smallest `ortho_height`, with the eye twice the box's radius away. `lens.near`, `far`,
    /// `ortho_height` are not used (the fit's own are).
    pub fn fit(
        lo: [f64; 3],
        hi: [f64; 3],
        azimuth: f64,
        elevation: f64,
        margin: f64,
        aspect: f64,
        lens: Lens,
    ) -> Result<Self> {
        check_angles(azimuth, elevation)?;
        check_z_scale(lens.z_scale)?;
        ensure((0.0..1.0).contains(&margin), "margin", || {
            format!("margin is {margin}; expected a fraction in [0, 1)")
        })?;
        ensure(aspect.is_finite() && aspect > 0.0, "aspect", || {
            format!("aspect is {aspect}; expected a finite number > 0")
        })?;
        ensure(lens.fov_y.is_finite() && lens.fov_y > 0.0 && lens.fov_y < 180.0, "fov_y", || {
            format!("fov_y is {}; expected degrees in the open interval (0, 180)", lens.fov_y)
        })?;
        for (p, arg) in [(lo, "bounds"), (hi, "bounds")] {
            ensure(p.iter().all(|c| c.is_finite()), arg, || format!("bounds {p:?} are not finite"))?;
        }
        let s = DVec3::new(1.0, 1.0, lens.z_scale);
        let (a, b) = (DVec3::from(lo) * s, DVec3::from(hi) * s);
        let (rlo, rhi) = (a.min(b), a.max(b));
        let centre = 0.5 * (rlo + rhi);
        let forward = -direction(azimuth, elevation);
        let probe = Camera { eye: DVec3::ZERO, target: forward, up: DVec3::from(lens.up), ..Camera::default_for_fit() };
        let up = probe.effective_up(forward);
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        let ty = (lens.fov_y.to_radians() / 2.0).tan() * (1.0 - margin);
        let tx = ty * aspect;
        let radius = 0.5 * (rhi - rlo).length();
        let (mut d, mut half_h, mut behind) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..8 {
            let c = DVec3::new(
                if i & 1 == 0 { rlo.x } else { rhi.x },
                if i & 2 == 0 { rlo.y } else { rhi.y },
                if i & 4 == 0 { rlo.z } else { rhi.z },
            ) - centre;
            let (x, y, z) = (c.dot(right), c.dot(up), c.dot(forward));
            // Inside when |x| <= (d + z) tx and |y| <= (d + z) ty (d + z: the corner's depth).
            d = d.max((x.abs() / tx).max(y.abs() / ty) - z);
            half_h = half_h.max(y.abs()).max(x.abs() / aspect);
            behind = behind.max(-z);
        }
        let target = (centre / s).into();
        let mut lens = Lens { near: None, far: None, ortho_height: None, ..lens };
        let distance = match lens.projection {
            Projection::Perspective => d.max(behind * (1.0 + 1e-9)).max(1e-6),
            Projection::Orthographic => {
                lens.ortho_height = Some((2.0 * half_h / (1.0 - margin)).max(super::MIN_ORTHO_HEIGHT));
                (2.0 * radius).max(1e-3)
            }
        };
        Camera::orbit(target, Orbit { azimuth, elevation, distance }, lens)
    }

    /// A placeholder whose only use is `effective_up` (which reads `up` alone).
    fn default_for_fit() -> Camera {
        let l = Lens::default();
        Camera {
            eye: DVec3::ZERO,
            target: DVec3::X,
            up: DVec3::from(l.up),
            fov_y: l.fov_y,
            near: None,
            far: None,
            projection: l.projection,
            ortho_height: None,
            z_scale: 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DVec3, b: [f64; 3]) -> bool {
        (a - DVec3::from(b)).length() < 1e-9
    }

    #[test]
    fn orbit_places_the_eye_by_compass_bearing() {
        let t = [10.0, 20.0, 5.0];
        let o =
            |az, el, d| Camera::orbit(t, Orbit { azimuth: az, elevation: el, distance: d }, Lens::default()).unwrap();
        assert!(close(o(0.0, 0.0, 2.0).eye, [10.0, 22.0, 5.0])); // north
        assert!(close(o(90.0, 0.0, 2.0).eye, [12.0, 20.0, 5.0])); // east
        assert!(close(o(180.0, 0.0, 2.0).eye, [10.0, 18.0, 5.0]));
        assert!(close(o(0.0, 90.0, 3.0).eye, [10.0, 20.0, 8.0])); // straight above
        let h = 2.0f64.sqrt();
        assert!(close(o(90.0, 45.0, 2.0).eye, [10.0 + h, 20.0, 5.0 + h]));
        // z_scale: the layout is in render space, so world z moves by 1/s.
        let c = Camera::orbit(
            t,
            Orbit { azimuth: 0.0, elevation: 90.0, distance: 4.0 },
            Lens { z_scale: 2.0, ..Lens::default() },
        );
        assert!(close(c.unwrap().eye, [10.0, 20.0, 7.0]));
    }

    #[test]
    fn angles_round_trip_and_moves() {
        let l = Lens { z_scale: 3.0, ..Lens::default() };
        let c = Camera::orbit([1.0, 2.0, 3.0], Orbit { azimuth: 300.0, elevation: 20.0, distance: 50.0 }, l).unwrap();
        let o = c.orbit_angles();
        assert!(
            (o.azimuth - 300.0).abs() < 1e-9 && (o.elevation - 20.0).abs() < 1e-9 && (o.distance - 50.0).abs() < 1e-9
        );
        let r = c.rotated(90.0, 10.0).unwrap().orbit_angles();
        assert_eq!(c.rotated(0.0, 100.0).unwrap().orbit_angles().elevation, 90.0);
        assert!(
            (r.azimuth - 30.0).abs() < 1e-9 && (r.elevation - 30.0).abs() < 1e-9 && (r.distance - 50.0).abs() < 1e-9
        );
        assert!((c.zoomed(2.0).unwrap().orbit_angles().distance - 25.0).abs() < 1e-9);
        let ortho =
            Camera::orbit([0.0; 3], o, Lens { projection: Projection::Orthographic, ortho_height: Some(8.0), ..l });
        let z = ortho.unwrap().zoomed(4.0).unwrap();
        assert_eq!(z.ortho_height, Some(2.0));
        assert!((z.orbit_angles().distance - 50.0).abs() < 1e-9);
    }

    #[test]
    fn bad_values_name_their_argument() {
        let o = Orbit { azimuth: 0.0, elevation: 0.0, distance: 1.0 };
        let arg = |r: Result<Camera>| r.unwrap_err().to_string().split([':', ' ']).next().unwrap().to_string();
        assert_eq!(arg(Camera::orbit([0.0; 3], Orbit { elevation: 91.0, ..o }, Lens::default())), "elevation");
        assert_eq!(arg(Camera::orbit([0.0; 3], Orbit { distance: 0.0, ..o }, Lens::default())), "distance");
        assert_eq!(arg(Camera::orbit([0.0; 3], Orbit { azimuth: f64::NAN, ..o }, Lens::default())), "azimuth");
        assert_eq!(arg(Camera::orbit([0.0; 3], o, Lens { z_scale: 0.0, ..Lens::default() })), "z_scale");
        let c = Camera::orbit([0.0; 3], o, Lens::default()).unwrap();
        assert_eq!(arg(c.zoomed(0.0)), "factor");
        assert_eq!(arg(c.rotated(f64::INFINITY, 0.0)), "d_azimuth");
        assert_eq!(arg(Camera::fit([0.0; 3], [1.0; 3], 0.0, 0.0, 1.0, 1.0, Lens::default())), "margin");
        assert_eq!(arg(Camera::fit([0.0; 3], [1.0; 3], 0.0, 0.0, 0.0, -1.0, Lens::default())), "aspect");
    }

    #[test]
    fn fit_frames_every_corner_and_is_tight() {
        let (lo, hi) = ([0.0, 0.0, -100.0], [4000.0, 3000.0, 0.0]);
        for (az, el, aspect) in [(30.0, 30.0, 1.0), (200.0, 10.0, 1.6), (0.0, 90.0, 0.5), (75.0, -20.0, 1.25)] {
            let c = Camera::fit(lo, hi, az, el, 0.0, aspect, Lens::default()).unwrap();
            let f = c.frame(DVec3::ZERO, None, aspect);
            let mut worst = 0.0f64;
            for i in 0..8 {
                let p = DVec3::new(
                    if i & 1 == 0 { lo[0] } else { hi[0] },
                    if i & 2 == 0 { lo[1] } else { hi[1] },
                    if i & 4 == 0 { lo[2] } else { hi[2] },
                );
                let q = f.view_proj.project_point3(p);
                worst = worst.max(q.x.abs()).max(q.y.abs());
            }
            // In NDC every corner lies within [-1, 1], and the extreme one touches the border.
            assert!((worst - 1.0).abs() < 1e-6, "az {az} el {el}: {worst}");
        }
    }
}

//! Tests of horizon culling against the CPU reference rasterizer (`crate::cull::reference`): no
//! tile with a visible pixel may be culled.

use super::tree::HorizonResult;
use super::{HeightGrid, HorizonTree};
use crate::cull::reference::{self, Depth, RefOut};
use glam::dcamera::rh::proj::{directx as dx_proj, opengl as gl_proj};
use glam::dcamera::rh::view::look_at_mat4;
use glam::{DMat4, DVec3};
use std::f64::consts::PI;

use crate::TestRng as Lcg;

struct Terrain {
    z: Vec<f32>,
    nx: usize,
    ny: usize,
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    tiles: (usize, usize),
}
impl Terrain {
    fn grid(&self) -> HeightGrid<'_> {
        HeightGrid {
            z: &self.z,
            nx: self.nx,
            ny: self.ny,
            x0: self.x0,
            y0: self.y0,
            dx: self.dx,
            dy: self.dy,
            tiles: self.tiles,
        }
    }
    fn zmax(&self) -> f64 {
        self.z.iter().filter(|v| v.is_finite()).fold(f64::NEG_INFINITY, |a, &b| a.max(b as f64))
    }
    fn zmin(&self) -> f64 {
        self.z.iter().filter(|v| v.is_finite()).fold(f64::INFINITY, |a, &b| a.min(b as f64))
    }
    fn extent(&self) -> (f64, f64) {
        ((self.nx - 1) as f64 * self.dx.abs(), (self.ny - 1) as f64 * self.dy.abs())
    }
    /// The full-resolution triangles of every tile for [`reference::rasterize`], with id = tile
    /// index `iy * tx + ix`: two per cell, (a, b, c) and (a, c, d) from corner (i, j)
    /// counter-clockwise; a triangle with a NaN corner is dropped by the reference.
    fn triangles(&self) -> Vec<(usize, [DVec3; 3])> {
        let (tx, ty) = self.tiles;
        let bx = crate::lod::tile_bounds(self.nx, tx);
        let by = crate::lod::tile_bounds(self.ny, ty);
        let pos = |i: usize, j: usize| {
            DVec3::new(self.x0 + i as f64 * self.dx, self.y0 + j as f64 * self.dy, self.z[j * self.nx + i] as f64)
        };
        let mut tris = Vec::new();
        for iy in 0..ty {
            for ix in 0..tx {
                let tile = iy * tx + ix;
                for j in by[iy]..by[iy + 1] {
                    for i in bx[ix]..bx[ix + 1] {
                        let a = pos(i, j);
                        let b = pos(i + 1, j);
                        let c = pos(i + 1, j + 1);
                        let d = pos(i, j + 1);
                        for tri in [[a, b, c], [a, c, d]] {
                            tris.push((tile, tri));
                        }
                    }
                }
            }
        }
        tris
    }
}

fn camera(eye: DVec3, fwd: DVec3, up: DVec3, ext: f64, w: usize, h: usize) -> DMat4 {
    let view = look_at_mat4(eye, eye + fwd, up);
    let proj = dx_proj::perspective(60f64.to_radians(), w as f64 / h as f64, 0.002 * ext, 20.0 * ext);
    proj * view
}

fn dir(az_deg: f64, pitch_deg: f64) -> DVec3 {
    let (a, p) = (az_deg.to_radians(), pitch_deg.to_radians());
    DVec3::new(p.cos() * a.cos(), p.cos() * a.sin(), p.sin())
}

struct Check {
    res: HorizonResult,
    rf: RefOut,
    violations: Vec<usize>,
    nonempty: usize,
    culled: usize,
    invisible: usize,
}

fn check_gl(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize, gl: bool) -> Check {
    check_depth(t, vp, eye, w, h, gl, false)
}

fn check_depth(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize, gl: bool, reverse: bool) -> Check {
    let tree = HorizonTree::build(&t.grid());
    let res = tree.cull(vp, eye, w as u32, h as u32);
    let n = t.tiles.0 * t.tiles.1;
    let rf = reference::rasterize(&t.triangles(), n, vp, w, h, Depth { gl, reverse });
    let mut violations = vec![];
    let (mut nonempty, mut culled, mut invisible) = (0, 0, 0);
    for i in 0..n {
        if rf.visible[i] && !res.tile_visible[i] {
            violations.push(i);
        }
        if tree.tile_nonempty[i] {
            nonempty += 1;
            if !res.tile_visible[i] {
                culled += 1;
            }
            if !rf.visible[i] {
                invisible += 1;
            }
        }
    }
    Check { res, rf, violations, nonempty, culled, invisible }
}

fn check(t: &Terrain, vp: DMat4, eye: DVec3, w: usize, h: usize) -> Check {
    check_gl(t, vp, eye, w, h, false)
}

fn print_tiles(t: &Terrain, c: &Check) {
    let (tx, ty) = t.tiles;
    for iy in (0..ty).rev() {
        let row: String = (0..tx)
            .map(|ix| {
                let i = iy * tx + ix;
                match (c.res.tile_visible[i], c.rf.visible[i]) {
                    (true, true) => 'V',   // kept, visible
                    (true, false) => 'k',  // kept, invisible
                    (false, false) => '.', // culled, invisible
                    (false, true) => '!',  // culled but visible: BUG
                }
            })
            .collect();
        println!("  iy={iy}: {row}");
    }
}

#[test]
fn ridge_hides_valley() {
    let (nx, ny) = (65, 65);
    let mut z = vec![0f32; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let y = j as f64;
            z[j * nx + i] = (12.0 * (-((y - 20.0) / 4.0).powi(2)).exp()
                + 0.3 * (i as f64 * 0.7).sin() * (y * 0.5).cos()
                + 0.3) as f32;
        }
    }
    let t = Terrain { z, nx, ny, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, tiles: (8, 8) };
    let (w, h) = (160, 120);
    let eye = DVec3::new(32.0, -20.0, 6.0);
    let vp = camera(eye, dir(90.0, -5.0), DVec3::Z, 64.0, w, h);
    let c = check(&t, vp, eye, w, h);
    println!(
        "ridge: culled {}/{} (reference-invisible {}), visited {}, culled nodes {}",
        c.culled, c.nonempty, c.invisible, c.res.nodes_visited, c.res.nodes_culled
    );
    print_tiles(&t, &c);
    assert!(c.res.culling_applied);
    assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
    // the valley behind the ridge (rows iy >= 4) must be culled, centre columns included
    for iy in 4..8 {
        for ix in 0..8 {
            let i = iy * 8 + ix;
            assert!(!c.rf.visible[i]);
            assert!(!c.res.tile_visible[i], "tile ({ix},{iy}) not culled");
        }
    }
    // the ridge itself is visible and kept
    for ix in 3..5 {
        assert!(c.res.tile_visible[2 * 8 + ix]);
    }
}

#[test]
fn flat_field_only_frustum_culls() {
    let (nx, ny) = (65, 65);
    let t = Terrain { z: vec![0.0; nx * ny], nx, ny, x0: -10.0, y0: 5.0, dx: 1.0, dy: 1.0, tiles: (8, 8) };
    let (w, h) = (160, 120);
    for (k, (ex, ey, az, pitch)) in
        [(22.0, 37.0, 30.0, 0.0), (22.0, 37.0, 200.0, -10.0), (-30.0, 0.0, 45.0, -5.0), (10.0, 30.0, 90.0, -25.0)]
            .into_iter()
            .enumerate()
    {
        let eye = DVec3::new(ex, ey, 5.0);
        let vp = camera(eye, dir(az, pitch), DVec3::Z, 64.0, w, h);
        let c = check(&t, vp, eye, w, h);
        println!("flat {k}: culled {}/{}, reference-invisible {}", c.culled, c.nonempty, c.invisible);
        print_tiles(&t, &c);
        assert!(c.res.culling_applied);
        assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
        for i in 0..64 {
            if !c.res.tile_visible[i] {
                assert!(!c.rf.has_frag[i], "tile {i} culled although inside the frustum");
            }
        }
    }
}

fn random_terrain(rng: &mut Lcg) -> Terrain {
    let nx = rng.irange(33, 65);
    let ny = rng.irange(33, 65);
    let tiles = (rng.irange(4, 8), rng.irange(4, 8));
    let dx = rng.range(0.5, 2.0);
    let dy = dx * rng.range(0.8, 1.25);
    let x0 = rng.range(-100.0, 100.0);
    let y0 = rng.range(-100.0, 100.0);
    let ext = ((nx - 1) as f64 * dx).max((ny - 1) as f64 * dy);
    let nw = rng.irange(1, 4);
    let waves: Vec<(f64, f64, f64, f64)> = (0..nw)
        .map(|_| {
            (
                ext * rng.range(0.01, 0.12),
                2.0 * PI / (ext * rng.range(0.15, 1.2)),
                rng.range(0.0, 2.0 * PI),
                rng.range(0.0, 2.0 * PI),
            )
        })
        .collect();
    let base = rng.range(-20.0, 20.0);
    let mut z = vec![0f32; nx * ny];
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (i as f64 * dx, j as f64 * dy);
            let v: f64 = waves.iter().map(|&(a, k, th, ph)| a * (k * (x * th.cos() + y * th.sin()) + ph).sin()).sum();
            z[j * nx + i] = (base + v) as f32;
        }
    }
    // holes
    let nh = rng.irange(0, 3);
    let noholes = std::env::var("NOHOLES").is_ok();
    for _ in 0..if noholes { 0 } else { nh } {
        let (ci, cj) = (rng.range(0.0, nx as f64), rng.range(0.0, ny as f64));
        let r = rng.range(0.8, 6.0);
        for j in 0..ny {
            for i in 0..nx {
                if (i as f64 - ci).powi(2) + (j as f64 - cj).powi(2) < r * r {
                    z[j * nx + i] = f32::NAN;
                }
            }
        }
    }
    let p = rng.range(0.0, 0.01);
    for v in z.iter_mut() {
        if rng.f() < p && !noholes {
            *v = f32::NAN;
        }
    }
    let mut t = Terrain { z, nx, ny, x0, y0, dx, dy, tiles };
    if rng.f() < 0.15 && !noholes {
        // an all-NaN tile
        let bx = crate::lod::tile_bounds(nx, tiles.0);
        let by = crate::lod::tile_bounds(ny, tiles.1);
        let (ix, iy) = (rng.irange(0, tiles.0 - 1), rng.irange(0, tiles.1 - 1));
        for j in by[iy]..=by[iy + 1] {
            for i in bx[ix]..=bx[ix + 1] {
                t.z[j * nx + i] = f32::NAN;
            }
        }
    }
    t
}

#[test]
fn property_random_low_cameras() {
    let mut rng = Lcg(0x1234_5678_9abc_def0);
    let (w, h) = (160, 120);
    let (mut sum_frac, mut sum_eff, mut n_eff) = (0.0, 0.0, 0);
    let (mut tot_culled, mut tot_nonempty, mut tot_invisible) = (0, 0, 0);
    let mut failures = vec![];
    let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(200);
    let mut occl = 0usize;
    for case in 0..ncases {
        let t = random_terrain(&mut rng);
        let (ex, ey) = t.extent();
        let ext = ex.max(ey);
        let eye = DVec3::new(
            t.x0 + rng.range(-0.3, 1.3) * ex,
            t.y0 + rng.range(-0.3, 1.3) * ey,
            t.zmax() + rng.range(0.02, 0.30) * ext,
        );
        let az = if rng.f() < 0.5 {
            rng.range(0.0, 360.0)
        } else {
            let c = DVec3::new(t.x0 + 0.5 * ex, t.y0 + 0.5 * ey, 0.0) - eye;
            c.y.atan2(c.x).to_degrees() + rng.range(-45.0, 45.0)
        };
        let pitch = rng.range(-30.0, 5.0);
        let vp = camera(eye, dir(az, pitch), DVec3::Z, ext, w, h);
        let c = check(&t, vp, eye, w, h);
        assert!(c.res.culling_applied);
        if !c.violations.is_empty() {
            println!("case {case}: VIOLATION tiles {:?}", c.violations);
            print_tiles(&t, &c);
            failures.push(case);
        }
        sum_frac += c.culled as f64 / c.nonempty.max(1) as f64;
        if c.invisible > 0 {
            sum_eff += c.culled as f64 / c.invisible as f64;
            n_eff += 1;
        }
        tot_culled += c.culled;
        tot_nonempty += c.nonempty;
        tot_invisible += c.invisible;
        occl += (0..c.res.tile_visible.len()).filter(|&i| !c.res.tile_visible[i] && c.rf.has_frag[i]).count();
    }
    let nc = ncases as f64;
    println!(
        "property: {ncases} cases, tiles culled by occlusion (inside the frustum): {occl} = {:.3} of non-empty",
        occl as f64 / tot_nonempty as f64
    );
    println!(
        "property: mean culled fraction {:.3} (total {}/{} = {:.3}); reference-invisible {:.3}; mean culled/invisible {:.3} over {} cases",
        sum_frac / nc,
        tot_culled,
        tot_nonempty,
        tot_culled as f64 / tot_nonempty as f64,
        tot_invisible as f64 / tot_nonempty as f64,
        sum_eff / n_eff.max(1) as f64,
        n_eff
    );
    assert!(failures.is_empty(), "violations in cases {failures:?}");
}

/// Extra: roll, any pitch within the allowed range, orthographic views, eye anywhere.
#[test]
fn property_roll_ortho_any_eye() {
    let mut rng = Lcg(42);
    let (w, h) = (128, 96);
    let (mut culled, mut nonempty, mut applied) = (0, 0, 0);
    let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(120);
    for case in 0..ncases {
        let t = random_terrain(&mut rng);
        let (ex, ey) = t.extent();
        let ext = ex.max(ey);
        let eye = DVec3::new(
            t.x0 + rng.range(-0.5, 1.5) * ex,
            t.y0 + rng.range(-0.5, 1.5) * ey,
            rng.range(t.zmin() - 0.1 * ext, t.zmax() + 0.5 * ext),
        );
        let f = dir(rng.range(0.0, 360.0), rng.range(-70.0, 70.0));
        let roll = rng.range(-40.0f64, 40.0).to_radians();
        let right = f.cross(DVec3::Z).normalize();
        let up0 = right.cross(f);
        let up = up0 * roll.cos() + right * roll.sin();
        let view = look_at_mat4(eye, eye + f, up);
        let gl = case % 4 == 1;
        let proj = if case % 3 == 0 {
            let s = rng.range(0.2, 0.8) * ext;
            let (l, r) = (-s * w as f64 / h as f64, s * w as f64 / h as f64);
            if gl {
                gl_proj::orthographic(l, r, -s, s, 0.0, 4.0 * ext)
            } else {
                dx_proj::orthographic(l, r, -s, s, 0.0, 4.0 * ext)
            }
        } else {
            let fov = rng.range(20.0f64, 90.0).to_radians();
            if gl {
                gl_proj::perspective(fov, w as f64 / h as f64, 0.002 * ext, 20.0 * ext)
            } else {
                dx_proj::perspective(fov, w as f64 / h as f64, 0.002 * ext, 20.0 * ext)
            }
        };
        let vp = proj * view;
        let c = check_gl(&t, vp, eye, w, h, gl);
        if c.res.culling_applied {
            applied += 1;
        }
        if !c.violations.is_empty() {
            print_tiles(&t, &c);
        }
        assert!(c.violations.is_empty(), "case {case}: visible tiles culled {:?}", c.violations);
        culled += c.culled;
        nonempty += c.nonempty;
    }
    println!("roll/ortho/any-eye: applied in {applied}/{ncases} views, culled {culled}/{nonempty}");
}

/// The renderer's projections: reverse-Z, infinite-far perspective and reverse-Z
/// orthographic (near -> depth 1), low eyes near the terrain, `Greater` depth test.
#[test]
fn property_reverse_z() {
    let mut rng = Lcg(2024);
    let (w, h) = (128, 96);
    let (mut culled, mut nonempty, mut applied, mut ortho_culled) = (0, 0, 0, 0);
    let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(160);
    for case in 0..ncases {
        let t = random_terrain(&mut rng);
        let (ex, ey) = t.extent();
        let ext = ex.max(ey);
        let eye = DVec3::new(
            t.x0 + rng.range(-0.3, 1.3) * ex,
            t.y0 + rng.range(-0.3, 1.3) * ey,
            t.zmax() + rng.range(0.005, 0.2) * ext,
        );
        let f = dir(rng.range(0.0, 360.0), rng.range(-30.0, 8.0));
        let view = look_at_mat4(eye, eye + f, DVec3::Z);
        let ortho = case % 3 == 0;
        let proj = if ortho {
            let s = rng.range(0.05, 0.5) * ext;
            let (l, r) = (-s * w as f64 / h as f64, s * w as f64 / h as f64);
            let near = if case % 2 == 0 { 0.0 } else { rng.range(0.0, 0.3) * ext };
            dx_proj::orthographic(l, r, -s, s, 4.0 * ext, near)
        } else {
            let fov = rng.range(20.0f64, 90.0).to_radians();
            let near = rng.range(0.0005, 0.05) * ext;
            dx_proj::perspective_infinite_reverse(fov, w as f64 / h as f64, near)
        };
        let vp = proj * view;
        let c = check_depth(&t, vp, eye, w, h, false, true);
        if c.res.culling_applied {
            applied += 1;
        }
        if !c.violations.is_empty() {
            print_tiles(&t, &c);
        }
        assert!(c.violations.is_empty(), "case {case} (ortho {ortho}): visible tiles culled {:?}", c.violations);
        culled += c.culled;
        nonempty += c.nonempty;
        if ortho {
            ortho_culled += c.culled;
        }
    }
    println!(
        "reverse-Z: applied in {applied}/{ncases} views, culled {culled}/{nonempty} (orthographic {ortho_culled})"
    );
    assert!(culled > 0 && ortho_culled > 0);
}

#[test]
fn straight_down_and_below_terrain() {
    let mut rng = Lcg(7);
    let t = random_terrain(&mut rng);
    let (ex, ey) = t.extent();
    let ext = ex.max(ey);
    let (w, h) = (128, 96);
    let centre = DVec3::new(t.x0 + 0.5 * ex, t.y0 + 0.5 * ey, 0.0);
    // straight down
    let eye = DVec3::new(centre.x, centre.y, t.zmax() + 0.5 * ext);
    let vp = camera(eye, -DVec3::Z, DVec3::Y, ext, w, h);
    let tree = HorizonTree::build(&t.grid());
    let r = tree.cull(vp, eye, w as u32, h as u32);
    assert!(!r.culling_applied);
    assert_eq!(r.tile_visible, tree.tile_nonempty);
    assert_eq!(r.horizon.len(), w);
    // eye below the terrain, looking in several directions
    for (az, pitch) in [(0.0, 0.0), (90.0, 20.0), (200.0, -20.0), (300.0, 45.0)] {
        let eye = DVec3::new(centre.x, centre.y, t.zmin() - 0.05 * ext);
        let vp = camera(eye, dir(az, pitch), DVec3::Z, ext, w, h);
        let c = check(&t, vp, eye, w, h);
        println!("below ({az},{pitch}): applied {} culled {}/{}", c.res.culling_applied, c.culled, c.nonempty);
        assert!(c.violations.is_empty(), "visible tiles culled: {:?}", c.violations);
    }
    // degenerate inputs: no panic
    let _ = tree.cull(DMat4::ZERO, eye, w as u32, h as u32);
    let _ = tree.cull(vp, eye, 0, 0);
    let _ = tree.cull(DMat4::from_cols_array(&[f64::NAN; 16]), eye, 10, 10);
    let empty =
        HorizonTree::build(&HeightGrid { z: &[], nx: 0, ny: 0, x0: 0.0, y0: 0.0, dx: 1.0, dy: 1.0, tiles: (2, 2) });
    let r = empty.cull(vp, eye, 8, 8);
    assert!(!r.culling_applied && r.tile_visible.len() == 4);
}

/// Rotated and yflipped grids (`cull_in_frame`): the tree is built in the grid's own frame
/// (dy < 0 for yflip), the reference rasterizes the triangles turned into render space by `frame`,
/// and no visible tile may be culled. Low views around the turned terrain, perspective and
/// reverse-Z orthographic, as the renderer draws.
#[test]
fn property_rotated_and_flipped_grids() {
    let mut rng = Lcg(0x5eed_0016);
    let (w, h) = (128, 96);
    // [unflipped, flipped]
    let (mut culled, mut nonempty) = ([0; 2], [0; 2]);
    let ncases: usize = std::env::var("HORIZON_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(120);
    for case in 0..ncases {
        let mut t = random_terrain(&mut rng);
        if case % 2 == 1 {
            t.dy = -t.dy; // yflip: rows towards -y in the grid's frame
        }
        let deg = [30.0, 90.0, 180.0, -75.0, rng.range(-180.0, 180.0)][case % 5];
        let (c, s) = crate::lod::cos_sin_deg(deg);
        let pivot = DVec3::new(t.x0, t.y0, 0.0);
        let rot = DMat4::from_cols(
            glam::DVec4::new(c, s, 0.0, 0.0),
            glam::DVec4::new(-s, c, 0.0, 0.0),
            glam::DVec4::Z,
            glam::DVec4::W,
        );
        let frame = DMat4::from_translation(pivot) * rot * DMat4::from_translation(-pivot);
        let (ex, ey) = t.extent();
        let ext = ex.max(ey);
        let centre = frame.transform_point3(DVec3::new(t.x0 + 0.5 * ex, t.y0 + 0.5 * t.dy.signum() * ey, 0.0));
        let eye = DVec3::new(
            centre.x + rng.range(-0.8, 0.8) * ext,
            centre.y + rng.range(-0.8, 0.8) * ext,
            t.zmax() + rng.range(0.01, 0.25) * ext,
        );
        let az = if rng.f() < 0.5 {
            rng.range(0.0, 360.0)
        } else {
            let d = centre - eye;
            d.y.atan2(d.x).to_degrees() + rng.range(-40.0, 40.0)
        };
        let f = dir(az, rng.range(-30.0, 5.0));
        let view = look_at_mat4(eye, eye + f, DVec3::Z);
        let ortho = case % 4 == 0;
        let proj = if ortho {
            let sc = rng.range(0.1, 0.5) * ext;
            let (l, r) = (-sc * w as f64 / h as f64, sc * w as f64 / h as f64);
            dx_proj::orthographic(l, r, -sc, sc, 4.0 * ext, 0.0)
        } else {
            dx_proj::perspective_infinite_reverse(60f64.to_radians(), w as f64 / h as f64, 0.002 * ext)
        };
        let vp = proj * view;
        let tree = HorizonTree::build(&t.grid());
        let res = tree.cull_in_frame(vp, frame, eye, w as u32, h as u32);
        let n = t.tiles.0 * t.tiles.1;
        let tris: Vec<(usize, [DVec3; 3])> =
            t.triangles().into_iter().map(|(id, tri)| (id, tri.map(|p| frame.transform_point3(p)))).collect();
        let rf = reference::rasterize(&tris, n, vp, w, h, Depth { gl: false, reverse: true });
        let violations: Vec<usize> = (0..n).filter(|&i| rf.visible[i] && !res.tile_visible[i]).collect();
        assert!(res.culling_applied, "case {case}");
        assert!(violations.is_empty(), "case {case} ({deg}°, dy {}): visible tiles culled {violations:?}", t.dy);
        for i in 0..n {
            if tree.tile_nonempty[i] {
                nonempty[case % 2] += 1;
                culled[case % 2] += usize::from(!res.tile_visible[i]);
            }
        }
    }
    println!("rotated/flipped: culled {culled:?} of {nonempty:?} (unflipped, flipped)");
    for k in 0..2 {
        assert!(culled[k] > nonempty[k] / 10, "culling should still cull: {culled:?}/{nonempty:?}");
    }
}

/// The identity frame is exactly the plain cull.
#[test]
fn identity_frame_is_plain_cull() {
    let mut rng = Lcg(99);
    let t = random_terrain(&mut rng);
    let (ex, ey) = t.extent();
    let eye = DVec3::new(t.x0 - 0.2 * ex, t.y0 + 0.5 * ey, t.zmax() + 0.1 * ex);
    let vp = camera(eye, dir(0.0, -10.0), DVec3::Z, ex.max(ey), 128, 96);
    let tree = HorizonTree::build(&t.grid());
    let a = tree.cull(vp, eye, 128, 96);
    let b = tree.cull_in_frame(vp, DMat4::IDENTITY, eye, 128, 96);
    assert_eq!((a.tile_visible, a.horizon, a.nodes_visited), (b.tile_visible, b.horizon, b.nodes_visited));
}

/// A tree built in object-local coordinates and culled with the object's offset in the matrix
/// (what the strategy caches, so `Scene::translate` rebuilds nothing) is as conservative as the
/// reference of the translated terrain, and culls as much as a tree built at the translated place.
#[test]
fn property_translated_tree_equals_tree_built_in_place() {
    let mut rng = Lcg(0x7a5c_0118);
    let (w, h) = (160, 120);
    let (mut same, mut culled_local, mut culled_moved) = (0, 0, 0);
    let ncases = 80;
    for case in 0..ncases {
        let local = random_terrain(&mut rng);
        let (ex, ey) = local.extent();
        let ext = ex.max(ey);
        // Offsets from small to UTM-sized (f32 round-off on the GPU grows with them).
        let mag = [0.0, 10.0, 1e3, 4.5e5][case % 4];
        let off = DVec3::new(rng.range(-1.0, 1.0) * mag, rng.range(-1.0, 1.0) * mag, rng.range(-1.0, 1.0) * mag * 0.01);
        let moved = Terrain {
            z: local.z.iter().map(|&v| (v as f64 + off.z) as f32).collect(),
            x0: local.x0 + off.x,
            y0: local.y0 + off.y,
            ..Terrain { z: Vec::new(), ..local }
        };
        let local_tree = HorizonTree::build(&local.grid());
        let (ex0, ey0) = (moved.x0, moved.y0);
        let eye = DVec3::new(
            ex0 + rng.range(-0.3, 1.3) * ex,
            ey0 + rng.range(-0.3, 1.3) * ey,
            moved.zmax() + rng.range(0.02, 0.30) * ext,
        );
        let c = DVec3::new(ex0 + 0.5 * ex, ey0 + 0.5 * ey, moved.zmin()) - eye;
        let az = c.y.atan2(c.x).to_degrees() + rng.range(-45.0, 45.0);
        let vp = camera(eye, dir(az, rng.range(-30.0, 5.0)), DVec3::Z, ext, w, h);
        // Reference and in-place tree of the moved terrain; the local tree culled with the offset.
        let c_moved = check(&moved, vp, eye, w, h);
        let res = local_tree.cull_translated(vp, off, eye, w as u32, h as u32);
        let n = res.tile_visible.len();
        let bad: Vec<usize> = (0..n).filter(|&i| c_moved.rf.visible[i] && !res.tile_visible[i]).collect();
        assert!(bad.is_empty(), "case {case} (offset {off}): visible tiles culled: {bad:?}");
        same += usize::from(res.tile_visible == c_moved.res.tile_visible);
        culled_local += res.tile_visible.iter().filter(|&&v| !v).count();
        culled_moved += c_moved.res.tile_visible.iter().filter(|&&v| !v).count();
    }
    println!("translated trees: same mask in {same}/{ncases} cases; culled {culled_local} vs {culled_moved} in place");
    assert!(same * 10 >= ncases * 9, "masks differ in {} cases", ncases - same);
    assert!(culled_local * 10 >= culled_moved * 9);
}

//! CPU reference rasterizer for culling tests (test-only).
//!
//! A software z-buffer that tells which objects a GPU shows: triangles in render (world) space,
//! each tagged with an id (a tile, an object, ...), are transformed by `view_proj`, clipped against
//! the near and far planes of the depth range, projected to the screen and sampled at pixel
//! centres. A culling test compares a strategy's result with [`rasterize`]: an id with a visible
//! pixel must not be culled.
//!
//! Conventions (those of the renderer and of [`crate::cull::horizon`]):
//! * `view_proj` maps render space to clip space: `w > 0` in front, NDC x and y in [-1, 1], y up;
//!   the depth range is OpenGL's `-w <= z <= w` or wgpu's `0 <= z <= w`, standard or reverse-Z
//!   ([`Depth`]);
//! * screen coordinates are `((x/w + 1) / 2 * width, (y/w + 1) / 2 * height)`; pixel `(px, py)` has
//!   its centre at `(px + 0.5, py + 0.5)`, so rows count from the bottom, and per-pixel buffers are
//!   indexed `py * width + px`;
//! * a pixel centre on a triangle's edge or within a relative tolerance of it belongs to the
//!   triangle (inclusive, slightly generous edges: no fragment the GPU produces is missed); an id
//!   is visible at a pixel if its depth there is within `1e-12` of the nearest;
//! * no back-face culling, no MSAA; x and y are not clipped (only pixels on the screen are
//!   sampled); triangles with a non-finite vertex coordinate are dropped (NaN heights are holes).

use glam::{DMat4, DVec3, DVec4};

/// Depth convention of the projection.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Depth {
    /// OpenGL clip depth range `-w <= z <= w`; otherwise wgpu/Vulkan/D3D `0 <= z <= w`.
    pub gl: bool,
    /// reverse-Z depth (larger z_ndc = nearer, as the renderer's `Greater` test); otherwise smaller
    /// z_ndc is nearer.
    pub reverse: bool,
}

/// What the reference image shows, per id and per pixel.
pub(crate) struct RefOut {
    /// id has >= 1 pixel where it is (within tolerance) the nearest surface
    pub visible: Vec<bool>,
    /// id produces >= 1 fragment at all (depth ignored)
    pub has_frag: Vec<bool>,
    /// per pixel (`py * width + px`, rows from the bottom): id and NDC depth `z/w` of the nearest
    /// fragment (the first such triangle in input order on ties), `None` where there is none
    #[allow(dead_code)] // not read by the horizon tests; for tests that need per-pixel results
    pub nearest: Vec<Option<(usize, f64)>>,
}

/// Clips a convex polygon (clip coordinates) to the depth range: `z >= 0` (`z >= -w` with `gl`)
/// and `z <= w`.
fn clip_poly(poly: &[DVec4], gl: bool) -> Vec<DVec4> {
    let mut p = poly.to_vec();
    for plane in 0..2 {
        let d = |v: &DVec4| {
            if plane == 0 {
                if gl {
                    v.z + v.w
                } else {
                    v.z
                }
            } else {
                v.w - v.z
            }
        };
        let mut out = Vec::with_capacity(p.len() + 2);
        for k in 0..p.len() {
            let a = p[k];
            let b = p[(k + 1) % p.len()];
            let (da, db) = (d(&a), d(&b));
            if da >= 0.0 {
                out.push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                let t = da / (da - db);
                out.push(a + (b - a) * t);
            }
        }
        p = out;
        if p.is_empty() {
            break;
        }
    }
    p
}

/// Software rasterizer: pixel-centre sampling (inclusive edges, generous), z-buffer.
/// `tris`: render-space triangles with an id `< n_ids` each; `view_proj` maps render space to clip
/// space (see the module doc); `depth.reverse`: reverse-Z depth (larger z_ndc = nearer, as the
/// renderer's `Greater` test).
pub(crate) fn rasterize(
    tris: &[(usize, [DVec3; 3])],
    n_ids: usize,
    view_proj: DMat4,
    width: usize,
    height: usize,
    depth: Depth,
) -> RefOut {
    let (vp, w, h, gl, reverse) = (view_proj, width, height, depth.gl, depth.reverse);
    // collect screen-space triangles with their id
    let mut screen: Vec<(usize, [DVec3; 3])> = Vec::new();
    for &(id, tri) in tris {
        if tri.iter().any(|p| !p.is_finite()) {
            continue;
        }
        let cl: Vec<DVec4> = tri.iter().map(|p| vp * p.extend(1.0)).collect();
        let poly = clip_poly(&cl, gl);
        if poly.len() < 3 || poly.iter().any(|c| c.w <= 1e-300) {
            continue;
        }
        let sp: Vec<DVec3> = poly
            .iter()
            .map(|c| {
                DVec3::new(
                    (c.x / c.w + 1.0) * 0.5 * w as f64,
                    (c.y / c.w + 1.0) * 0.5 * h as f64,
                    if reverse { -c.z / c.w } else { c.z / c.w },
                )
            })
            .collect();
        for k in 1..sp.len() - 1 {
            screen.push((id, [sp[0], sp[k], sp[k + 1]]));
        }
    }
    let raster = |tri: &[DVec3; 3], f: &mut dyn FnMut(usize, f64)| {
        let [a, b, c] = *tri;
        let area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        if area.abs() < 1e-14 {
            return;
        }
        let minx = a.x.min(b.x).min(c.x);
        let maxx = a.x.max(b.x).max(c.x);
        let miny = a.y.min(b.y).min(c.y);
        let maxy = a.y.max(b.y).max(c.y);
        let px0 = (minx - 0.5 - 1e-3).ceil().max(0.0);
        let px1 = (maxx - 0.5 + 1e-3).floor().min(w as f64 - 1.0);
        let py0 = (miny - 0.5 - 1e-3).ceil().max(0.0);
        let py1 = (maxy - 0.5 + 1e-3).floor().min(h as f64 - 1.0);
        if px0 > px1 || py0 > py1 {
            return;
        }
        let edge = |p: DVec3, q: DVec3, x: f64, y: f64| (q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x);
        for py in py0 as usize..=py1 as usize {
            for px in px0 as usize..=px1 as usize {
                let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
                let l0 = edge(b, c, x, y) / area;
                let l1 = edge(c, a, x, y) / area;
                let l2 = edge(a, b, x, y) / area;
                let tol = -1e-7;
                if l0 >= tol && l1 >= tol && l2 >= tol {
                    f(py * w + px, l0 * a.z + l1 * b.z + l2 * c.z);
                }
            }
        }
    };
    // depth (smaller = nearer: z_ndc negated for reverse-Z) and id of the nearest fragment
    let mut zbuf = vec![f64::INFINITY; w * h];
    let mut zid = vec![usize::MAX; w * h];
    for (id, tri) in &screen {
        raster(tri, &mut |i, d| {
            if d < zbuf[i] {
                zbuf[i] = d;
                zid[i] = *id;
            }
        });
    }
    let mut visible = vec![false; n_ids];
    let mut has_frag = vec![false; n_ids];
    for (id, tri) in &screen {
        raster(tri, &mut |i, d| {
            has_frag[*id] = true;
            if d <= zbuf[i] + 1e-12 {
                visible[*id] = true;
            }
        });
    }
    let nearest = zbuf
        .iter()
        .zip(&zid)
        .map(|(&d, &id)| (id != usize::MAX).then_some((id, if reverse { -d } else { d })))
        .collect();
    RefOut { visible, has_frag, nearest }
}

//! Tests of the marching-cubes extraction and its patch cache.

use super::super::octree::MinMaxOctree;
use super::super::{pesco_synthetic, sphere_field};
use super::*;
use std::collections::BTreeMap;
use std::time::Instant;

use crate::TestRng as Lcg;

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn centroid(p: &[[f64; 3]]) -> [f64; 3] {
    let n = p.len() as f64;
    [0, 1, 2].map(|i| p.iter().map(|q| q[i]).sum::<f64>() / n)
}

/// Uniform f32 in [0, 1) from the top 24 bits.
fn unit(rng: &mut Lcg) -> f32 {
    (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32
}

type PosKey = [u64; 3];
fn pk(p: [f64; 3]) -> PosKey {
    p.map(f64::to_bits)
}

/// Welds by bit-identical position; returns (unique positions, triangles
/// as welded ids, with degenerate ones dropped).
fn weld(patch: &SurfacePatch) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut ids: HashMap<PosKey, u32> = HashMap::new();
    let mut pos = Vec::new();
    let map: Vec<u32> = patch
        .positions
        .iter()
        .map(|&p| {
            *ids.entry(pk(p)).or_insert_with(|| {
                pos.push(p);
                pos.len() as u32 - 1
            })
        })
        .collect();
    let tris = patch
        .triangles
        .iter()
        .map(|t| t.map(|i| map[i as usize]))
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    (pos, tris)
}

/// Sorted triangles as position triples, rotated to a canonical start
/// (keeps winding).
fn tri_set(patch: &SurfacePatch) -> Vec<[PosKey; 3]> {
    let mut v: Vec<[PosKey; 3]> = patch
        .triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| pk(patch.positions[i as usize]));
            let m = (0..3).min_by_key(|&r| p[r]).unwrap();
            [p[m], p[(m + 1) % 3], p[(m + 2) % 3]]
        })
        .collect();
    v.sort();
    v
}

fn vertex_set(patch: &SurfacePatch) -> Vec<PosKey> {
    let mut v: Vec<PosKey> = patch.positions.iter().map(|&p| pk(p)).collect();
    v.sort();
    v.dedup();
    v
}

fn assert_closed_oriented(patch: &SurfacePatch) {
    let (_, tris) = weld(patch);
    assert!(!tris.is_empty());
    let mut directed: BTreeMap<(u32, u32), u32> = BTreeMap::new();
    for t in &tris {
        for e in 0..3 {
            *directed.entry((t[e], t[(e + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &n) in &directed {
        assert_eq!(n, 1, "directed edge {a}->{b} used {n} times");
        assert_eq!(directed.get(&(b, a)), Some(&1), "edge {a}-{b} is a border or non-manifold");
    }
}

fn area(patch: &SurfacePatch) -> f64 {
    patch
        .triangles
        .iter()
        .map(|t| {
            let p = t.map(|i| patch.positions[i as usize]);
            let c = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            0.5 * dot(c, c).sqrt()
        })
        .sum()
}

fn full(vol: &Volume, w: f32) -> SurfacePatch {
    extract(vol, w, [0; 3], [u32::MAX; 3])
}

#[test]
fn per_node_matches_whole_volume() {
    let mut rng = Lcg(7);
    let vols = vec![pesco_synthetic(37), sphere_field(29, 0.63), {
        // random field with some NaNs, odd dims
        let dims = (13, 9, 21);
        let v: Vec<f32> = (0..dims.0 * dims.1 * dims.2)
            .map(|_| if unit(&mut rng) < 0.03 { f32::NAN } else { unit(&mut rng) - 0.5 })
            .collect();
        Volume::new(v.into(), dims, [0.25, 1.0, -3.0], [0.3, 0.7, 0.11]).unwrap()
    }];
    for vol in &vols {
        let w = 0.0;
        let whole = full(vol, w);
        assert!(!whole.is_empty());
        let tree = MinMaxOctree::build(vol);
        for d in [tree.max_depth(), tree.max_depth().saturating_sub(2), 0] {
            let nodes = tree.straddling_at_depth(w, d);
            let patches = extract_nodes(vol, w, &nodes);
            let joined = SurfacePatch::concat(&patches);
            assert_eq!(joined.triangle_count(), whole.triangle_count(), "depth {d}");
            assert_eq!(vertex_set(&joined), vertex_set(&whole), "depth {d}");
            assert_eq!(tri_set(&joined), tri_set(&whole), "depth {d}");
            // non-straddling nodes yield nothing
            for n in tree.nodes_at_depth(d) {
                if !n.straddles(w) {
                    assert!(extract(vol, w, n.cell_lo, n.cell_hi).is_empty());
                }
            }
        }
        // serial == parallel chunked
        let cells = vol.cells();
        let serial = extract_serial(
            vol,
            &vol.window([0; 3], [vol.nx - 1, vol.ny - 1, vol.nz - 1]),
            w,
            [0; 3],
            cells,
            false,
            &|_| true,
        )
        .patch;
        assert_eq!(serial.triangle_count(), whole.triangle_count());
        assert_eq!(tri_set(&serial), tri_set(&whole));
        assert_eq!(serial.vertex_count(), whole.vertex_count());
    }
}

/// Extracting the cells a filter keeps gives, node by node, exactly the triangles of those cells
/// in the whole node's patch (positions, normals and order), only their vertices, and empty
/// cells elsewhere.
#[test]
fn kept_cells_give_the_triangles_of_those_cells() {
    let vol = pesco_synthetic(24);
    let w = 0.0;
    let tree = MinMaxOctree::build(&vol);
    let nodes = tree.straddling_at_depth(w, tree.max_depth() - 2);
    let keep = |[i, j, k]: [usize; 3]| (i * 7 + j * 3 + k * 5) % 4 != 0;
    let some = extract_nodes_where(&vol, w, &nodes, &keep);
    let whole = extract_nodes(&vol, w, &nodes);
    let mut kept_any = 0;
    for ((n, a), b) in nodes.iter().zip(&some).zip(&whole) {
        assert_eq!(a.cell_starts.len(), b.cell_starts.len());
        let mut c = 0;
        let mut used = std::collections::BTreeSet::new();
        for k in n.cell_lo[2]..n.cell_hi[2] {
            for j in n.cell_lo[1]..n.cell_hi[1] {
                for i in n.cell_lo[0]..n.cell_hi[0] {
                    let (ta, tb) = (
                        &a.triangles[a.cell_starts[c] as usize..a.cell_starts[c + 1] as usize],
                        &b.triangles[b.cell_starts[c] as usize..b.cell_starts[c + 1] as usize],
                    );
                    c += 1;
                    if !keep([i as usize, j as usize, k as usize]) {
                        assert!(ta.is_empty());
                        continue;
                    }
                    assert_eq!(ta.len(), tb.len());
                    kept_any += ta.len();
                    for (x, y) in ta.iter().zip(tb) {
                        for (&u, &v) in x.iter().zip(y) {
                            assert_eq!(a.positions[u as usize], b.positions[v as usize]);
                            assert_eq!(a.normals[u as usize], b.normals[v as usize]);
                            used.insert(v);
                        }
                    }
                }
            }
        }
        assert_eq!(a.vertex_count(), used.len());
    }
    assert!(kept_any > 0);
}

#[test]
fn sphere_closed_area_normals() {
    let r = 0.7;
    let vol = sphere_field(64, r);
    let p = full(&vol, 0.0);
    assert_closed_oriented(&p);
    let a = area(&p);
    let exact = 4.0 * std::f64::consts::PI * r * r;
    let err = (a - exact).abs() / exact;
    println!("sphere n=64: {} tris, area {a:.5} vs {exact:.5} ({:.3}%)", p.triangle_count(), err * 100.0);
    assert!(err < 0.02);
    // vertices on the sphere, normals outward, winding agrees with normals
    for (q, n) in p.positions.iter().zip(&p.normals) {
        let len = dot(*q, *q).sqrt();
        assert!((len - r).abs() < 0.01);
        let nn = n.map(|x| x as f64);
        assert!((dot(nn, nn).sqrt() - 1.0).abs() < 1e-5);
        assert!(dot(nn, *q) / len > 0.95);
    }
    for t in &p.triangles {
        let q = t.map(|i| p.positions[i as usize]);
        let c = cross(sub(q[1], q[0]), sub(q[2], q[0]));
        let centre = centroid(&q);
        assert!(dot(c, centre) >= 0.0);
    }
    // patches per octree node, joined, are also closed (crack-free)
    let tree = MinMaxOctree::build(&vol);
    for d in [tree.max_depth(), tree.max_depth() - 2, 1] {
        let nodes = tree.straddling_at_depth(0.0, d);
        let joined = SurfacePatch::concat(&extract_nodes(&vol, 0.0, &nodes));
        assert_closed_oriented(&joined);
    }
}

#[test]
fn samples_exactly_at_isovalue() {
    // isovalue hitting samples exactly: no panic, still closed after welding
    let vol = sphere_field(21, 0.5);
    let vals: Vec<f32> = vol.values.iter().map(|v| (v * 10.0).round() / 10.0).collect();
    let q = Volume::new(vals.into(), (21, 21, 21), vol.origin, vol.spacing).unwrap();
    let p = full(&q, 0.0);
    assert_closed_oriented(&p);
}

#[test]
fn no_surface_cases() {
    let vol = sphere_field(17, 0.5);
    // wholly above: every value >= w
    assert!(full(&vol, -10.0).is_empty());
    // wholly below
    assert!(full(&vol, 10.0).is_empty());
    // constant field equal to w counts as above
    let c = Volume::new(vec![1.0f32; 27].into(), (3, 3, 3), [0.0; 3], [1.0; 3]).unwrap();
    assert!(full(&c, 1.0).is_empty());
    // empty / out-of-range boxes
    assert!(extract(&vol, 0.0, [5, 5, 5], [5, 9, 9]).is_empty());
    assert!(extract(&vol, 0.0, [100, 0, 0], [200, 9, 9]).is_empty());
    assert!(full(&vol, f32::NAN).is_empty());
}

#[test]
fn nan_handling() {
    let mut rng = Lcg(99);
    let base = pesco_synthetic(24);
    let vals: Vec<f32> = base.values.iter().map(|&v| if unit(&mut rng) < 0.1 { f32::NAN } else { v }).collect();
    let vol = Volume::new(vals.into(), (24, 24, 24), base.origin, base.spacing).unwrap();
    let p = full(&vol, 0.0);
    assert!(!p.is_empty());
    assert!(p.positions.iter().flatten().all(|x| x.is_finite()));
    assert!(p.normals.iter().flatten().all(|x| x.is_finite()));
    let tree = MinMaxOctree::build(&vol);
    let nodes = tree.straddling_at_depth(0.0, tree.max_depth() - 1);
    let joined = SurfacePatch::concat(&extract_nodes(&vol, 0.0, &nodes));
    assert_eq!(tri_set(&joined), tri_set(&p));
    // all-NaN volume
    let nanv = Volume::new(vec![f32::NAN; 64].into(), (4, 4, 4), [0.0; 3], [1.0; 3]).unwrap();
    assert!(full(&nanv, 0.0).is_empty());
    let t = MinMaxOctree::build(&nanv);
    assert!(t.straddling_at_depth(0.0, 5).is_empty());
}

#[test]
fn cache_reuses_patches() {
    let vol = pesco_synthetic(33);
    let tree = MinMaxOctree::build(&vol);
    let nodes = tree.straddling_at_depth(0.0, 3);
    let mut cache = PatchCache::new();
    let a = cache.get_or_extract_many(&vol, 0.0, &nodes);
    assert_eq!(cache.len(), nodes.len());
    let b = cache.get_or_extract_many(&vol, 0.0, &nodes);
    assert_eq!(a.len(), b.len());
    assert!(a.iter().zip(&b).all(|(x, y)| Arc::ptr_eq(x, y)));
    assert!(Arc::ptr_eq(&cache.get(-0.0, &nodes[0]).unwrap(), &a[0]));
    // duplicates in one request share one patch
    let dup = vec![nodes[0], nodes[0]];
    let c = cache.get_or_extract_many(&vol, 0.0, &dup);
    assert!(Arc::ptr_eq(&c[0], &c[1]) && Arc::ptr_eq(&c[0], &a[0]));
    // another isovalue adds entries
    let _ = cache.get_or_extract_many(&vol, 0.5, &nodes[..1]);
    assert_eq!(cache.len(), nodes.len() + 1);
    cache.retain_isovalue(0.0);
    assert_eq!(cache.len(), nodes.len());
    // a different volume clears the cache
    let other = pesco_synthetic(33);
    let d = cache.get_or_extract_many(&other, 0.0, &nodes[..1]);
    assert_eq!(cache.len(), 1);
    assert!(!Arc::ptr_eq(&d[0], &a[0]));
    assert_eq!(*d[0], *a[0]);
    cache.clear();
    assert!(cache.is_empty());
}

#[test]
fn cache_is_lru_within_its_budget() {
    let vol = pesco_synthetic(33);
    let tree = MinMaxOctree::build(&vol);
    let level = |w: f32| tree.straddling_at_depth(w, 3);
    let mut probe = PatchCache::new();
    probe.get_or_extract_many(&vol, 0.0, &level(0.0));
    let one = probe.bytes();
    assert!(one > 0);
    assert_eq!(one, level(0.0).iter().map(|n| patch_bytes(&probe.get(0.0, n).unwrap())).sum::<usize>());
    // room for about two isovalues' patches
    let mut cache = PatchCache::with_budget(one * 2 + one / 2);
    for w in [0.0, 0.3, 0.0, 0.6, -0.4, 0.2] {
        cache.get_or_extract_many(&vol, w, &level(w));
        assert!(cache.bytes() <= cache.budget(), "{} > {}", cache.bytes(), cache.budget());
        let held: usize = [0.0f32, 0.3, 0.6, -0.4, 0.2]
            .iter()
            .flat_map(|&v| level(v).into_iter().map(move |n| (v, n)))
            .filter_map(|(v, n)| cache.get(v, &n))
            .map(|p| patch_bytes(&p))
            .sum();
        assert_eq!(cache.bytes(), held);
    }
    // the last isovalue is whole; the oldest (0.3, then 0.0) went first
    assert!(level(0.2).iter().all(|n| cache.get(0.2, n).is_some()));
    assert!(level(0.3).iter().all(|n| cache.get(0.3, n).is_none()));
    cache.set_budget(0);
    assert!(cache.is_empty() && cache.bytes() == 0);
    // a patch handed out survives its eviction
    let kept = cache.get_or_extract_many(&vol, 0.0, &level(0.0));
    assert!(cache.is_empty() && kept.iter().any(|p| !p.is_empty()));
}

#[test]
fn timing_pesco() {
    for n in [128usize, 256] {
        let t0 = Instant::now();
        let vol = pesco_synthetic(n);
        let t_vol = t0.elapsed();
        let t1 = Instant::now();
        let tree = MinMaxOctree::build(&vol);
        let t_tree = t1.elapsed();
        let t2 = Instant::now();
        let p = full(&vol, 0.0);
        let t_full = t2.elapsed();
        let t3 = Instant::now();
        let nodes = tree.straddling_at_depth(0.0, tree.max_depth().saturating_sub(4));
        let patches = extract_nodes(&vol, 0.0, &nodes);
        let t_nodes = t3.elapsed();
        let nt: usize = patches.iter().map(|p| p.triangle_count()).sum();
        assert_eq!(nt, p.triangle_count());
        println!(
            "pesco_synthetic({n}) on {} threads: sample {:?}, octree {:?}, full extract {:?} \
             -> {} triangles, {} vertices; {} straddling nodes at depth {} extract {:?}",
            rayon::current_num_threads(),
            t_vol,
            t_tree,
            t_full,
            p.triangle_count(),
            p.vertex_count(),
            nodes.len(),
            tree.max_depth().saturating_sub(4),
            t_nodes
        );
    }
}

/// A random field (uniform in [-1, 1)) whose border samples are 1: its isosurface at 0 is closed
/// and full of ambiguous faces.
fn random_closed(rng: &mut Lcg, n: usize) -> Volume {
    let v: Vec<f32> = (0..n * n * n)
        .map(|k| {
            let (i, j, l) = (k % n, (k / n) % n, k / (n * n));
            if [i, j, l].iter().any(|&c| c == 0 || c == n - 1) {
                1.0
            } else {
                2.0 * unit(rng) - 1.0
            }
        })
        .collect();
    Volume::new(v.into(), (n, n, n), [0.0; 3], [1.0, 0.5, 2.0]).unwrap()
}

#[test]
fn random_fields_are_watertight_across_nodes_and_chunks() {
    let mut rng = Lcg(2024);
    for n in [6usize, 11, 34] {
        let vol = random_closed(&mut rng, n);
        let whole = full(&vol, 0.0);
        assert_closed_oriented(&whole);
        let tree = MinMaxOctree::build(&vol);
        for d in 0..=tree.max_depth() {
            let joined = SurfacePatch::concat(&extract_nodes(&vol, 0.0, &tree.straddling_at_depth(0.0, d)));
            assert_closed_oriented(&joined);
            assert_eq!(tri_set(&joined), tri_set(&whole), "n {n} depth {d}");
        }
    }
}

#[test]
fn vertices_lie_on_the_trilinear_isosurface() {
    let mut rng = Lcg(5);
    for vol in [pesco_synthetic(23), random_closed(&mut rng, 12)] {
        let w = 0.1f32;
        let p = full(&vol, w);
        assert!(!p.is_empty());
        let (mut on_edges, mut scale) = (0, 0.0f64);
        for x in vol.values.iter() {
            scale = scale.max((*x as f64 - w as f64).abs());
        }
        for q in &p.positions {
            let g = [0, 1, 2].map(|a| (q[a] - vol.origin[a]) / vol.spacing[a]);
            let c = [0, 1, 2].map(|a| (g[a].floor() as usize).min(vol.cells()[a] - 1));
            let t = [0, 1, 2].map(|a| g[a] - c[a] as f64);
            // only edge vertices (two coordinates on grid lines); loop centroids are not on it
            if t.iter().filter(|&&x| x.abs() < 1e-9 || (x - 1.0).abs() < 1e-9).count() < 2 {
                continue;
            }
            on_edges += 1;
            let mut f = 0.0;
            for corner in 0..8usize {
                let b = [corner & 1, (corner >> 1) & 1, corner >> 2];
                let wgt: f64 = (0..3).map(|a| if b[a] == 1 { t[a] } else { 1.0 - t[a] }).product();
                f += wgt * vol.get(c[0] + b[0], c[1] + b[1], c[2] + b[2]) as f64;
            }
            // linear interpolation along the edge in f64 from f32 samples: rounding only
            assert!((f - w as f64).abs() <= 1e-9 * scale.max(1.0), "{f} at {q:?}");
        }
        assert!(on_edges as f64 > 0.99 * p.vertex_count() as f64);
    }
}

#[test]
fn cell_starts_index_each_cells_triangles() {
    let vol = pesco_synthetic(41);
    // a small box (serial) and the whole volume (parallel z-chunks)
    for (lo, hi) in [([3u32, 5, 7], [17u32, 12, 30]), ([0; 3], [40; 3])] {
        let p = extract(&vol, 0.0, lo, hi);
        let n = [0, 1, 2].map(|a| (hi[a] - lo[a]) as usize);
        assert_eq!(p.cell_starts.len(), n[0] * n[1] * n[2] + 1);
        assert_eq!(*p.cell_starts.last().unwrap() as usize, p.triangle_count());
        assert!(p.cell_starts.windows(2).all(|w| w[0] <= w[1]));
        for (c, w) in p.cell_starts.windows(2).enumerate() {
            let cell = [c % n[0], (c / n[0]) % n[1], c / (n[0] * n[1])];
            for t in &p.triangles[w[0] as usize..w[1] as usize] {
                for &v in t {
                    let q = p.positions[v as usize];
                    for a in 0..3 {
                        let g = (q[a] - vol.origin[a]) / vol.spacing[a] - lo[a] as f64 - cell[a] as f64;
                        assert!((-1e-9..=1.0 + 1e-9).contains(&g), "cell {cell:?} vertex {q:?}");
                    }
                }
            }
        }
    }
}

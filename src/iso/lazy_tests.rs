//! A lazy volume ([`Volume::lazy`] over a [`Resident`] store) gives what the resident volume gives:
//! the octree, extraction, planes, range, bytes, mesh; reading only what it needs.

use std::sync::Arc;

use super::march::{extract, extract_nodes};
use super::mesh::isosurface_mesh;
use super::store::{BrickCache, Resident, BRICK};
use super::{pesco_synthetic, MinMaxOctree, Volume};

fn lazy_of(v: &Volume, budget: usize) -> Volume {
    let dims = [v.nx, v.ny, v.nz];
    let store = BrickCache::new(Box::new(Resident { values: v.values.clone(), dims }), dims, budget);
    Volume::lazy(Arc::new(store), v.offset, (v.nx, v.ny, v.nz), v.origin, v.spacing).unwrap()
}

/// A field with NaN holes, non-cubic, with sizes that are not multiples of the bricks.
fn field() -> Volume {
    let p = pesco_synthetic(45);
    let (nx, ny, nz) = (45, 40, 37);
    let vals: Vec<f32> = (0..nx * ny * nz)
        .map(|k| {
            let (i, j, kk) = (k % nx, k / nx % ny, k / (nx * ny));
            if (i * 7 + j * 3 + kk) % 97 == 5 {
                f32::NAN
            } else {
                p.get(i, j, kk)
            }
        })
        .collect();
    Volume::new(vals.into(), (nx, ny, nz), [1.0, -2.0, 0.5], [0.5, 0.25, 1.0]).unwrap()
}

#[test]
fn lazy_octree_extraction_and_planes_equal_the_resident_ones() {
    let v = field();
    let t = MinMaxOctree::build(&v);
    for budget in [0, 4 * BRICK * BRICK * BRICK * 2, 64 << 20] {
        let l = lazy_of(&v, budget);
        let lt = MinMaxOctree::try_build(&l).unwrap();
        assert_eq!(lt.max_depth(), t.max_depth());
        for d in 0..=t.max_depth() {
            assert_eq!(lt.nodes_at_depth(d), t.nodes_at_depth(d), "depth {d}");
        }
        assert_eq!(l.finite_range(), v.finite_range(), "set by the build");
        for w in [0.0f32, 0.7, -1.2] {
            let nodes = t.straddling_at_depth(w, t.max_depth() - 2);
            assert_eq!(extract_nodes(&l, w, &nodes), extract_nodes(&v, w, &nodes));
            assert_eq!(extract(&l, w, [0; 3], [64; 3]), extract(&v, w, [0; 3], [64; 3]), "parallel chunks");
            assert_eq!(extract(&l, w, [3, 5, 7], [20, 9, 30]), extract(&v, w, [3, 5, 7], [20, 9, 30]));
        }
        let m = isosurface_mesh(&l, &lt, 0.3).unwrap();
        let n = isosurface_mesh(&v, &t, 0.3).unwrap();
        assert_eq!((m.vertices, m.faces), (n.vertices, n.faces));
        assert!(l.store().unwrap().peak_bytes() as usize <= budget);
        for (axis, index) in [(0, 0), (1, 17), (2, 36)] {
            let r = [(0, 44), (2, 30), (1, 36)];
            let before = l.bytes_read();
            let (a, b) = (l.plane(axis, index, r), v.plane(axis, index, r));
            assert!(a.0 == b.0 && a.2 == b.2);
            assert!(a.1.iter().zip(&b.1).all(|(x, y)| x.to_bits() == y.to_bits()), "plane values");
            let plane: usize = (0..3).filter(|&a| a != axis).map(|a| r[a].1 - r[a].0 + 1).product();
            // The bricks the plane crosses (`BrickCache::read_plane`): read through the cache
            // where they fit in a quarter of the budget, else the plane alone.
            let bricks: usize = (0..3)
                .map(|a| {
                    let (lo, hi) = if a == axis { (index, index) } else { r[a] };
                    let n = [v.nx, v.ny, v.nz][a];
                    ((hi / BRICK + 1) * BRICK).min(n) - lo / BRICK * BRICK
                })
                .product();
            let read = l.bytes_read() - before;
            if 4 * bricks <= budget / 4 {
                assert!(
                    read <= 4 * bricks as u64,
                    "at most the plane's bricks, once: budget {budget}, axis {axis}, read {read}, bricks {bricks}"
                );
                let again = l.bytes_read();
                assert_eq!(l.plane(axis, index, r).1.len(), b.1.len());
                assert_eq!(l.bytes_read(), again, "held in the cache");
            } else {
                assert_eq!(read, 4 * plane as u64, "a plane reads its samples alone");
            }
        }
        assert_eq!(l.to_bytes(), v.to_bytes());
        l.take_error().unwrap();
    }
}

#[test]
fn a_lazy_volume_reads_only_the_nodes_it_extracts() {
    let v = pesco_synthetic(129);
    let l = lazy_of(&v, 16 << 20);
    let t = MinMaxOctree::try_build(&l).unwrap();
    let built = l.bytes_read();
    // One pass, each slab sharing one layer with the one before.
    assert!(built as usize <= 4 * 129 * 129 * 129 * 9 / 8 + 4 * 129 * 129, "{built}");
    let nodes = t.nodes_at_depth(t.stored_depth());
    let few: Vec<_> = nodes.iter().filter(|n| n.ix < 2 && n.iy < 2 && n.iz < 2).copied().collect();
    extract_nodes(&l, 0.0, &few);
    // 16³ cells and their ring (samples 0..=17): the corner's brick of 32³ alone.
    assert_eq!(l.bytes_read() - built, 4 * (BRICK * BRICK * BRICK) as u64);
    extract_nodes(&l, 0.5, &few);
    assert_eq!(l.bytes_read() - built, 4 * (BRICK * BRICK * BRICK) as u64, "cached");
}

#[test]
fn infinite_samples_and_read_errors_name_values() {
    let mut vals = vec![0.0f32; 5 * 4 * 3];
    vals[37] = f32::INFINITY;
    let v = Volume::new(vals.into(), (5, 4, 3), [0.0; 3], [1.0; 3]).unwrap();
    let e = MinMaxOctree::try_build(&lazy_of(&v, 1 << 20)).unwrap_err().to_string();
    assert!(e.starts_with("values:") && e.contains("[1, 3, 2]") && e.contains("infinite"), "{e}");
    let store = BrickCache::new(Box::new(Resident { values: vec![0.0; 8].into(), dims: [2, 2, 2] }), [2, 2, 2], 0);
    let e = Volume::lazy(Arc::new(store), 0.0, (3, 2, 2), [0.0; 3], [1.0; 3]).unwrap_err().to_string();
    assert!(e.starts_with("values:"), "{e}");
}

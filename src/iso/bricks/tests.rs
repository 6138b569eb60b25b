use super::*;

/// The definition, brick by brick.
fn brute(classes: &[u8], d: [usize; 3], s: u32) -> Vec<u8> {
    let b = 1usize << s;
    let bd = d.map(|v| v.div_ceil(b));
    let mut out = Vec::new();
    for bz in 0..bd[2] {
        for by in 0..bd[1] {
            for bx in 0..bd[0] {
                let bb = [bx, by, bz];
                let lo = bb.map(|v| (v * b).saturating_sub(1));
                let hi: Vec<usize> = (0..3).map(|a| (bb[a] * b + b + 1).min(d[a])).collect();
                let mut seen = std::collections::HashSet::new();
                for z in lo[2]..hi[2] {
                    for y in lo[1]..hi[1] {
                        for x in lo[0]..hi[0] {
                            seen.insert(classes[(z * d[1] + y) * d[0] + x]);
                        }
                    }
                }
                let k = *seen.iter().next().unwrap();
                out.push(if seen.len() == 1 && (k == CLASS_BELOW || k == CLASS_ABOVE) { k } else { 0 });
            }
        }
    }
    out
}

#[test]
fn bricks_match_their_definition() {
    let mut state = 12345u64;
    let mut rnd = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 33) as usize
    };
    for d in [[23usize, 17, 9], [16, 16, 16], [5, 40, 33], [1, 1, 70]] {
        // Large uniform regions with a few other nodes sprinkled in.
        let n = d[0] * d[1] * d[2];
        let mut cls: Vec<u8> = (0..n).map(|i| if (i / d[0] / d[1]) < d[2] / 2 { 1 } else { 2 }).collect();
        for _ in 0..n / 97 + 1 {
            cls[rnd() % n] = (rnd() % 4) as u8;
        }
        let dims = d.map(|v| v as u32);
        let [(f, fd), (c, cd)]: [_; 2] = brick_classes(&cls, dims, &[1, 3]).try_into().unwrap();
        assert_eq!(f, brute(&cls, d, 1), "{d:?}");
        assert_eq!(c, brute(&cls, d, 3), "{d:?}");
        assert_eq!(fd, d.map(|v| v.div_ceil(2) as u32));
        assert_eq!(cd, d.map(|v| v.div_ceil(8) as u32));
    }
}

/// `skip_reach` against its definition on random grids of skippable bricks (two classes, and
/// gaps), with large uniform blocks so that reaches grow past a few bricks.
#[test]
fn skip_reach_matches_its_definition() {
    let d = [13u32, 9, 11];
    let n = (d[0] * d[1] * d[2]) as usize;
    let mut seed = 7u64;
    let mut rand = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (seed >> 33) as u32
    };
    let mut most = 0;
    for round in 0..6 {
        let mut skip = vec![0u8; n];
        for (i, b) in skip.iter_mut().enumerate() {
            let [x, y, z] = [i as u32 % d[0], i as u32 / d[0] % d[1], i as u32 / (d[0] * d[1])];
            // A block of class 1 and one of class 2, holes scattered over both.
            let k = if x < 7 { 1 } else { 2 };
            let hole = rand() % 100 < [0, 2, 5, 10, 30, 60][round] || (y == 4 && z == 5 && round % 2 == 1);
            *b = if hole { 0 } else { 4 | k };
        }
        let r = skip_reach(&skip, d);
        for (i, &ri) in r.iter().enumerate() {
            let p = [i as u32 % d[0], i as u32 / d[0] % d[1], i as u32 / (d[0] * d[1])].map(|v| v as i64);
            // The largest r: every brick within r - 1 (in the grid) skippable of this class.
            let fits = |r: i64| {
                (0..n).all(|j| {
                    let q = [j as u32 % d[0], j as u32 / d[0] % d[1], j as u32 / (d[0] * d[1])].map(|v| v as i64);
                    let far = (0..3).map(|a| (q[a] - p[a]).abs()).max().unwrap() > r - 1;
                    far || (skip[j] != 0 && skip[j] & 3 == skip[i] & 3)
                })
            };
            let want =
                if skip[i] == 0 { 0 } else { (1..=REACH_CAP as i64).take_while(|&r| fits(r)).last().unwrap_or(0) };
            assert_eq!(ri as i64, want, "round {round} brick {p:?}");
            most = most.max(want);
        }
    }
    assert!(most >= 4, "reaches of several bricks seen ({most})");
}

#[test]
fn leaf_node_classes_match_the_octree() {
    let mut vol = super::super::sphere_field(13, 0.5);
    let mut v: Vec<f32> = vol.values.to_vec();
    for i in (0..v.len()).step_by(211) {
        v[i] = f32::NAN;
    }
    vol.values = v.into();
    let tree = MinMaxOctree::build(&vol);
    for w in [0.0, 0.3, -0.2] {
        let md = tree.max_depth();
        let slow = tree.map_at_depth(md, |min, max, nan| match classify_range(min, max, w) {
            _ if nan => CLASS_NAN,
            Class::Below => CLASS_BELOW,
            Class::Above => CLASS_ABOVE,
            _ => CLASS_PASS,
        });
        let leaves = leaf_nodes(&vol.values, [vol.nx, vol.ny, vol.nz], w);
        assert_eq!(leaves.iter().map(|&k| k & 15).collect::<Vec<_>>(), slow, "classes, bits 2-3 clear");
        assert_eq!(node_classes(&tree, w, md), slow);
    }
}

#[test]
fn leaf_node_faces_match_their_corners() {
    let mut vol = super::super::sphere_field(11, 0.5);
    let mut v: Vec<f32> = vol.values.to_vec();
    for i in (0..v.len()).step_by(97) {
        v[i] = f32::NAN;
    }
    v[5] = 0.3; // a sample on the isovalue below
    vol.values = v.into();
    let (nx, ny, nz) = (vol.nx, vol.ny, vol.nz);
    let s = |x: usize, y: usize, z: usize| vol.values[(z * ny + y) * nx + x];
    for w in [0.0f32, 0.3] {
        let leaves = leaf_nodes(&vol.values, [nx, ny, nz], w);
        let (got, cls): (Vec<u8>, Vec<u8>) = leaves.iter().map(|&k| (k >> 4, k & 3)).unzip();
        let class = |c: [f32; 4]| {
            if c.iter().all(|&v| v < w) {
                1
            } else if c.iter().all(|&v| v > w) {
                2
            } else {
                0
            }
        };
        // A face's class from leaf_nodes' bits: uniform, and the side of the low corner.
        let decode = |b: u8, a: u32| match (b >> a & 1, b >> 3 & 1) {
            (0, _) => 0,
            (_, 1) => 1,
            _ => 2,
        };
        let mut n = [0; 3];
        for k in 0..nz - 1 {
            for j in 0..ny - 1 {
                for i in 0..nx - 1 {
                    let fx = class([s(i, j, k), s(i, j + 1, k), s(i, j, k + 1), s(i, j + 1, k + 1)]);
                    let fy = class([s(i, j, k), s(i + 1, j, k), s(i, j, k + 1), s(i + 1, j, k + 1)]);
                    let fz = class([s(i, j, k), s(i + 1, j, k), s(i, j + 1, k), s(i + 1, j + 1, k)]);
                    let c = (k * (ny - 1) + j) * (nx - 1) + i;
                    let f = [0, 1, 2].map(|a| decode(got[c], a));
                    assert_eq!(f, [fx, fy, fz], "cell ({i}, {j}, {k}), w {w}");
                    assert_eq!(got[c] >> 3, (s(i, j, k) < w) as u8);
                    // A Below / Above cell's faces are of its class.
                    if cls[c] == CLASS_BELOW || cls[c] == CLASS_ABOVE {
                        assert_eq!(f, [cls[c]; 3]);
                    }
                    for (a, f) in [fx, fy, fz].into_iter().enumerate() {
                        n[a] += (f != 0) as u32;
                    }
                }
            }
        }
        assert!(n.iter().all(|&c| c > 100), "{n:?}");
    }
}

#[test]
fn occluders_partition_the_classified_volume() {
    let vol = super::super::sphere_field(17, 0.5);
    let tree = MinMaxOctree::build(&vol);
    let (b, a) = occluder_nodes(&tree, 0.0, tree.max_depth());
    assert!(b.iter().all(|n| n.max < 0.0) && a.iter().all(|n| n.min > 0.0));
    let cells = |v: &[NodeInfo]| v.iter().map(|n| n.cell_count()).sum::<u64>();
    let leaves = tree.nodes_at_depth(tree.max_depth());
    let nb = leaves.iter().filter(|n| n.max < 0.0).count() as u64;
    let na = leaves.iter().filter(|n| n.min > 0.0).count() as u64;
    assert_eq!((cells(&b), cells(&a)), (nb, na));
}

#[test]
fn dilate_nan_reaches_the_26_neighbours() {
    let d = [7u32, 6, 5];
    let n = (d[0] * d[1] * d[2]) as usize;
    let idx = |x: u32, y: u32, z: u32| ((z * d[1] + y) * d[0] + x) as usize;
    let mut c = vec![CLASS_BELOW; n];
    c[idx(2, 2, 2)] = CLASS_NAN;
    c[idx(6, 5, 4)] = CLASS_NAN;
    c[idx(4, 0, 0)] = CLASS_PASS;
    let orig = c.clone();
    // Bits 4-7 (a leaf's faces) ride along untouched.
    let mut with_faces: Vec<u8> = c.iter().enumerate().map(|(i, &k)| k | ((i % 16) as u8) << 4).collect();
    let changed = dilate_nan(&mut c, d);
    assert_eq!(dilate_nan(&mut with_faces, d), changed);
    assert!(with_faces.iter().enumerate().all(|(i, &k)| k == c[i] | ((i % 16) as u8) << 4));
    let mut expect = 0;
    for z in 0..d[2] {
        for y in 0..d[1] {
            for x in 0..d[0] {
                let near = |q: [u32; 3]| [x, y, z].iter().zip(q).all(|(&a, b)| a.abs_diff(b) <= 1);
                let nan = near([2, 2, 2]) || near([6, 5, 4]);
                let want = if nan { CLASS_NAN } else { orig[idx(x, y, z)] };
                assert_eq!(c[idx(x, y, z)], want, "{x} {y} {z}");
                expect += (nan && orig[idx(x, y, z)] != CLASS_NAN) as usize;
            }
        }
    }
    assert_eq!(changed, expect);
    assert_eq!(changed, 26 + 7);
    let mut clean = vec![CLASS_ABOVE; n];
    assert_eq!(dilate_nan(&mut clean, d), 0);
}

#[test]
fn contour_bricks_hold_the_corners_of_bricks_with_surface() {
    // 11 x 9 x 6 samples: 10 x 8 x 5 cells, bricks 3 x 2 x 2 (partial at the high ends).
    let s = [11usize, 9, 6];
    let values: Vec<f32> = (0..s[0] * s[1] * s[2])
        .map(|i| {
            let (x, y, z) = (i % s[0], i / s[0] % s[1], i / (s[0] * s[1]));
            // Surface near x = 8.5 (bricks bx = 2), a blob at (1, 1, 1), a NaN at a far corner.
            if (x, y, z) == (1, 1, 1) {
                5.0
            } else if (x, y, z) == (0, 8, 5) {
                f32::NAN
            } else {
                x as f32 - 8.5
            }
        })
        .collect();
    let classes: Vec<u8> = leaf_nodes(&values, s, 0.0).iter().map(|&k| k & 3).collect();
    let passable = |bx: usize, by: usize, bz: usize| {
        (0..4).any(|z| {
            (0..4).any(|y| {
                (0..4).any(|x| {
                    let c = [4 * bx + x, 4 * by + y, 4 * bz + z];
                    c[0] < 10 && c[1] < 8 && c[2] < 5 && classes[(c[2] * 8 + c[1]) * 10 + c[0]] == CLASS_PASS
                })
            })
        })
    };
    let with: Vec<[u32; 3]> = (0..12)
        .map(|i| [i % 3, i / 3 % 2, i / 6])
        .filter(|p| passable(p[0] as usize, p[1] as usize, p[2] as usize))
        .collect();
    assert_eq!(with.len(), 5, "bx = 2 (4 bricks) and the blob's brick");
    let (words, nb) = contour_bricks(&values, s, &with);
    assert_eq!(nb, 3 * 2 * 2);
    assert_eq!(words.len(), nb + with.len() * 125);
    for i in 0..nb {
        let p = [i % 3, i / 3 % 2, i / 6];
        let slot = with.iter().position(|q| q.map(|v| v as usize) == p);
        assert_eq!(words[i], slot.map_or(NO_BLOCK, |k| k as u32), "brick {p:?}");
        let Some(k) = slot else { continue };
        let n = CONTOUR_SAMPLES;
        for (q, &w) in words[nb + k * n * n * n..][..n * n * n].iter().enumerate() {
            let c = [4 * p[0] + q % n, 4 * p[1] + q / n % n, 4 * p[2] + q / (n * n)];
            let c = [c[0].min(s[0] - 1), c[1].min(s[1] - 1), c[2].min(s[2] - 1)];
            assert_eq!(w, values[(c[2] * s[1] + c[1]) * s[0] + c[0]].to_bits(), "brick {p:?} sample {q}");
        }
    }
    // The octree's bricks (straddling nodes two levels up) hold every brick with a passable
    // cell: the walk never lacks a block it needs.
    let vol = crate::iso::Volume::new(values.clone().into(), (s[0], s[1], s[2]), [0.0; 3], [1.0; 3]).unwrap();
    let tree = crate::iso::MinMaxOctree::build(&vol);
    let (words, nb) = tree.contour_bricks(&tree.straddling_at_depth(0.0, tree.max_depth() - CONTOUR_SHIFT));
    assert_eq!(nb, 12);
    for p in &with {
        assert_ne!(words[((p[2] * 2 + p[1]) * 3 + p[0]) as usize], NO_BLOCK, "{p:?}");
    }
}

#[test]
fn pack_nodes_holds_classes_and_bricks() {
    // Below under z = 9.5, Above over it, one passable node: skippable bricks of both classes
    // at the fine level, Below ones at the coarse level, none near the passable node.
    let d = [37usize, 21, 41];
    let mut v: Vec<u8> =
        (0..d[0] * d[1] * d[2]).map(|i| if i / (d[0] * d[1]) < 10 { CLASS_BELOW } else { CLASS_ABOVE }).collect();
    v[(30 * d[1] + 5) * d[0] + 5] = CLASS_PASS;
    let dims = d.map(|x| x as u32);
    // Faces in bits 4-7 (pack_nodes keeps them, and reads only the class bits).
    let leaves: Vec<u8> = v.iter().enumerate().map(|(i, &k)| k | ((i % 16) as u8) << 4).collect();
    let (p, skip, _) = pack_nodes(&leaves, dims, false);
    assert!(skip.is_empty(), "no skip table without `huge`");
    assert_eq!(p.len(), 10 * 6 * 11 * 64, "whole bricks of 4³ nodes");
    let fine = brute(&v, d, FINE_SHIFT);
    let coarse = brute(&v, d, COARSE_SHIFT);
    let at = |b: &[u8], s: u32, i: usize| {
        let bd = d.map(|x| x.div_ceil(1 << s));
        b[(((i / (d[0] * d[1])) >> s) * bd[1] + ((i / d[0] % d[1]) >> s)) * bd[0] + ((i % d[0]) >> s)]
    };
    let mut seen = [0; 2];
    let mut read = vec![false; p.len()];
    for (i, &k) in v.iter().enumerate() {
        let q = [(i % d[0]) as u32, (i / d[0] % d[1]) as u32, (i / (d[0] * d[1])) as u32];
        let at_byte = brick_index(dims, q);
        read[at_byte] = true;
        let byte = p[at_byte] as u32;
        let (f, c) = (at(&fine, FINE_SHIFT, i) != 0, at(&coarse, COARSE_SHIFT, i) != 0);
        let want = k as u32 | (f as u32) << 2 | ((f && c) as u32) << 3 | (i as u32 % 16) << 4;
        assert_eq!(byte, want, "node {i}");
        seen[0] += f as u32;
        seen[1] += c as u32;
    }
    assert!(seen[0] > 0 && seen[1] > 0, "{seen:?}");
    assert!(p.iter().zip(&read).all(|(&b, &r)| r || b == 0), "zeros where no node is");
    assert_ne!(v.len() % 16, 0, "pack2's last word is partial");
    // pack2 reads the class bits of the nodes as of the classes alone.
    assert_eq!(pack2(&leaves), pack2(&v));
    // class_counts counts the packed classes as the bytes say (the padding not counted).
    let mut v2 = v.clone();
    for (i, k) in v2.iter_mut().enumerate() {
        if i % 7 == 3 {
            *k = CLASS_NAN;
        }
    }
    let want = [CLASS_BELOW, CLASS_ABOVE, CLASS_NAN].map(|k| v2.iter().filter(|&&x| x == k).count() as u32);
    assert!(want.iter().all(|&n| n > 0));
    assert_eq!(class_counts(&pack2(&v2)), want);
    // The skip table (with `huge`) holds per brick the byte all its nodes hold when it is a
    // skippable fine brick: here those whose faces depend on the class alone, as leaf nodes'
    // do, the others 0 (their nodes' bytes differ).
    let alike: Vec<u8> = v.iter().map(|&k| k | (k & 1) << 7 | 0x70).collect();
    for (nodes, some) in [(&alike, true), (&leaves, false)] {
        let (p, skip, huge) = pack_nodes(nodes, dims, true);
        assert!(huge.is_some());
        assert_eq!(skip.len(), p.len() / 64);
        for (b, (&s, brick)) in skip.iter().zip(p.chunks(64)).enumerate() {
            let all_alike = brick.iter().all(|&x| x == brick[0]);
            let want = if brick[0] & 4 != 0 && all_alike { brick[0] } else { 0 };
            assert_eq!(s, want, "brick {b}");
        }
        assert_eq!(skip.iter().any(|&s| s != 0), some);
    }
    let q = pack2(&v);
    for (i, &k) in v.iter().enumerate() {
        assert_eq!(node_class(&q, dims, [(i % d[0]) as u32, (i / d[0] % d[1]) as u32, (i / (d[0] * d[1])) as u32]), k);
    }
}

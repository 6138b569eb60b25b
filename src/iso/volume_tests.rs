//! Tests of `Volume` (its checks, bytes, lazy and rotated forms).

use super::*;

#[test]
fn damaged_volume_bytes_name_data() {
    // The volume's own checks named `spacing` (an argument the caller never passed).
    let v = Volume::from_f64(&[0.0; 8], (2, 2, 2), [0.0; 3], [1.0; 3]).unwrap();
    let mut b = v.to_bytes();
    b[8 + 4 + 24 + 24..8 + 4 + 24 + 32].copy_from_slice(&0f64.to_le_bytes()); // spacing.x
    let e = Volume::from_bytes(&b).unwrap_err().to_string();
    assert!(e.starts_with("data: damaged volume bytes: spacing: component 0 is 0"), "{e}");
}
use crate::scene::Scene;

#[test]
fn finite_range_is_the_extremes_of_the_finite_values() {
    // f64 samples around 1e8 (stored as residuals about an offset), NaNs among them, more
    // than one parallel chunk.
    let n = (70, 50, 40);
    let vals: Vec<f64> = (0..n.0 * n.1 * n.2)
        .map(|k| if k % 7 == 3 { f64::NAN } else { 1e8 + ((k * 7919) % 1000) as f64 - 500.0 })
        .collect();
    let v = Volume::from_f64(&vals, n, [0.0; 3], [1.0; 3]).unwrap();
    let want = vals
        .iter()
        .filter(|x| x.is_finite())
        .fold([f64::INFINITY, f64::NEG_INFINITY], |[a, b], &x| [a.min(x), b.max(x)]);
    assert_eq!(v.finite_range(), Some(want));
    assert_eq!(v.finite_range(), Some(want), "cached");
    let nan = Volume::new(vec![f32::NAN; 8].into(), (2, 2, 2), [0.0; 3], [1.0; 3]).unwrap();
    assert_eq!(nan.finite_range(), None);
}

#[test]
fn volume_new_validates() {
    let v: Arc<[f32]> = vec![0.0; 8].into();
    assert!(Volume::new(v.clone(), (2, 2, 2), [0.0; 3], [1.0; 3]).is_ok());
    assert!(Volume::new(v.clone(), (2, 2, 3), [0.0; 3], [1.0; 3]).is_err());
    assert!(Volume::new(v.clone(), (8, 1, 1), [0.0; 3], [1.0; 3]).is_err());
    assert!(Volume::new(v.clone(), (2, 2, 2), [0.0; 3], [0.0, 1.0, 1.0]).is_err());
    assert!(Volume::new(v, (2, 2, 2), [f64::NAN, 0.0, 0.0], [1.0; 3]).is_err());
}

#[test]
fn volume_indexing_and_bounds() {
    let vals: Vec<f32> = (0..24).map(|x| x as f32).collect();
    let v = Volume::new(vals.into(), (2, 3, 4), [1.0, 2.0, 3.0], [0.5, 1.0, 2.0]).unwrap();
    assert_eq!(v.get(1, 0, 0), 1.0);
    assert_eq!(v.get(0, 1, 0), 2.0);
    assert_eq!(v.get(0, 0, 1), 6.0);
    assert_eq!(v.get(1, 2, 3), 23.0);
    let (lo, hi) = v.bounds();
    assert_eq!(lo, [1.0, 2.0, 3.0]);
    assert_eq!(hi, [1.5, 4.0, 9.0]);
}

#[test]
fn f64_values_keep_their_precision_about_the_offset() {
    // 1e8 +- 1: as plain f32 every sample would be 1e8 and no isosurface at 1e8 would exist.
    let n = 9;
    let vals: Vec<f64> = (0..n * n * n).map(|k| 1e8 + ((k % n) as f64 - 4.0) / 4.0).collect();
    let v = Volume::from_f64(&vals, (n, n, n), [0.0; 3], [1.0; 3]).unwrap();
    assert_eq!(v.offset, 1e8);
    assert_eq!(v.get(0, 0, 0), -1.0);
    assert_eq!(v.value(v.get(8, 0, 0)), 1e8 + 1.0);
    assert_eq!(v.residual(1e8 + 0.5, "isovalue").unwrap(), 0.5);
    let shifted =
        Volume::from_f64(&vals.iter().map(|x| x - 1e8).collect::<Vec<_>>(), (n, n, n), [0.0; 3], [1.0; 3]).unwrap();
    let a = super::march::extract(&v, v.residual(1e8, "w").unwrap(), [0; 3], [8; 3]);
    let b = super::march::extract(&shifted, shifted.residual(0.0, "w").unwrap(), [0; 3], [8; 3]);
    assert!(a.triangle_count() > 0);
    assert_eq!(a, b);
    let t = MinMaxOctree::build(&v);
    assert_eq!((v.value(t.root().min), v.value(t.root().max)), (1e8 - 1.0, 1e8 + 1.0));
    // errors name the argument
    assert!(v.residual(f64::NAN, "isovalue").unwrap_err().to_string().starts_with("isovalue"));
    assert!(v.residual(1e300, "isovalue").unwrap_err().to_string().starts_with("isovalue"));
    let mut bad = vals.clone();
    bad[5] = f64::INFINITY;
    let e = Volume::from_f64(&bad, (n, n, n), [0.0; 3], [1.0; 3]).unwrap_err().to_string();
    assert!(e.starts_with("values[0, 0, 5]"), "{e}");
    bad[5] = -3e38;
    bad[6] = 3e38; // each fits f32, their range about the midrange (0) too
    assert!(Volume::from_f64(&bad, (n, n, n), [0.0; 3], [1.0; 3]).is_ok());
    bad[6] = 1e300;
    let e = Volume::from_f64(&bad, (n, n, n), [0.0; 3], [1.0; 3]).unwrap_err().to_string();
    assert!(e.starts_with("values[0, 0, "), "{e}");
}

#[test]
fn bytes_round_trip() {
    let vals: Vec<f64> = (0..60).map(|k| 1e8 + k as f64 * 0.25 + if k == 7 { f64::NAN } else { 0.0 }).collect();
    let v = Volume::from_f64(&vals, (3, 4, 5), [1.0, 2.0, 3.0], [0.5, 1.0, 2.0]).unwrap();
    let v = v.with_rotation(-37.5).unwrap();
    let w = Volume::from_bytes(&v.to_bytes()).unwrap();
    assert_eq!((w.offset, w.origin, w.spacing, (w.nx, w.ny, w.nz)), (v.offset, v.origin, v.spacing, (3, 4, 5)));
    assert_eq!(w.rotation, -37.5);
    // version 1 (no rotation) reads as unrotated: magic 8, version 4, dims 24, origin/spacing 48, offset 8
    let b2 = v.to_bytes();
    let mut b1 = [&b2[..92], &b2[100..]].concat();
    b1[8..12].copy_from_slice(&1u32.to_le_bytes());
    assert_eq!(Volume::from_bytes(&b1).unwrap().rotation, 0.0);
    assert_eq!(
        w.values.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        v.values.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );
    let b = v.to_bytes();
    assert!(Volume::from_bytes(&b[..b.len() - 2]).unwrap_err().to_string().starts_with("data"));
    assert!(Volume::from_bytes(&Scene::new().to_bytes()).unwrap_err().to_string().contains("magic"));
}

#[test]
fn synthetic_fields() {
    let p = pesco_synthetic(11);
    assert_eq!(p.bounds(), ([-5.0; 3], [5.0; 3]));
    // at (0,0,0): sin(0) + cos(-8)
    let f = (0.0f64.sin() + (-8.0f64).cos()) as f32;
    assert_eq!(p.get(5, 5, 5), f);
    let s = sphere_field(5, 0.5);
    assert_eq!(s.get(2, 2, 2), -0.5);
    assert_eq!(s.get(4, 2, 2), 0.5);
}

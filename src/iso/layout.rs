//! How a user's array maps onto a [`super::Volume`], which stores `values[(k*ny + j)*nx + i]`
//! (x fastest) with sample `(i,j,k)` at `origin + (i,j,k) * spacing`, z up.
//!
//! * [`AxisOrder`]: `"zyx"`: the array is indexed `[k, j, i]` (numpy's (nz, ny, nx), the stored
//!   order); `"xyz"`: it is indexed `[i, j, k]`: segyio's (inline, crossline, sample) cubes and
//!   xtgeo's `Cube.values` (ncol, nrow, nlay). The first index is then x, the second y, the last z.
//! * [`ZPositive`]: `"up"`: z grows with the sample index; `"down"`: the sample axis grows
//!   downwards (depth or two-way time), and the z of `origin` and `spacing` are on that axis: the
//!   sample of index k lies at world `z = -(origin_z + k * dz)`, so `origin_z` is the shallowest
//!   sample's depth (or time) and the volume renders the right way up in a z-up world. The stored
//!   grid then runs upwards from the deepest sample ([`stored_origin`]).
//!
//! The binding applies both as views of the user's array (a transpose, a reversed axis) and copies
//! the samples once into the volume's buffer (`Volume::from_f32_slices` / `from_f64_slices`).

use crate::error::{ensure, input_err, Result};

/// Index order of a user's 3-D array.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AxisOrder {
    /// `[k, j, i]`: (nz, ny, nx), the stored order.
    Zyx,
    /// `[i, j, k]`: (nx, ny, nz), e.g. segyio (inline, crossline, sample), xtgeo (ncol, nrow, nlay).
    Xyz,
}

impl AxisOrder {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "zyx" => Ok(Self::Zyx),
            "xyz" => Ok(Self::Xyz),
            _ => Err(input_err(
                "order",
                format!(
                    "order is {s:?}; expected \"zyx\" (values[k, j, i], numpy's (nz, ny, nx)) or \"xyz\" \
                     (values[i, j, k], e.g. segyio's (inline, crossline, sample))"
                ),
            )),
        }
    }
}

/// Direction of a user's z (sample) axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ZPositive {
    Up,
    /// Depth or time: the sample index and the given z coordinates grow downwards.
    Down,
}

impl ZPositive {
    pub fn parse(s: &str) -> Result<Self> {
        match s {
            "up" => Ok(Self::Up),
            "down" => Ok(Self::Down),
            _ => Err(input_err(
                "z_positive",
                format!(
                    "z_positive is {s:?}; expected \"up\" (z grows with the sample index) or \"down\" (depth or \
                     time: the sample axis grows downwards)"
                ),
            )),
        }
    }
}

/// The stored grid's origin (world position of stored sample (0, 0, 0), z up) for a user's
/// `origin` and `spacing` with `nz` samples along z: `origin` itself for [`ZPositive::Up`];
/// for [`ZPositive::Down`] the deepest sample, `z = -(origin_z + (nz - 1) dz)` (the stored z index
/// is then `nz - 1 - k`). Values are checked by [`check_grid`].
pub fn stored_origin(origin: [f64; 3], spacing: [f64; 3], nz: usize, z: ZPositive) -> [f64; 3] {
    match z {
        ZPositive::Up => origin,
        ZPositive::Down => [origin[0], origin[1], -(origin[2] + nz.saturating_sub(1) as f64 * spacing[2])],
    }
}

/// Checks a user's origin (finite) and spacing (finite, > 0) before any sample is read, as
/// `Volume::new` will; a negative dz says how to give a z axis that grows downwards.
pub fn check_grid(origin: [f64; 3], spacing: [f64; 3], z: ZPositive) -> Result<()> {
    for (i, o) in origin.iter().enumerate() {
        ensure(o.is_finite(), "origin", || format!("component {i} is {o}; expected a finite number"))?;
    }
    for (i, d) in spacing.iter().enumerate() {
        ensure(d.is_finite() && *d > 0.0, "spacing", || {
            let hint = if i == 2 && *d < 0.0 && z == ZPositive::Up {
                " (for a depth or time axis that grows downwards pass z_positive=\"down\" with dz > 0)"
            } else {
                ""
            };
            format!("component {i} is {d}; expected a finite number > 0{hint}")
        })?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_origins() {
        assert_eq!(AxisOrder::parse("xyz").unwrap(), AxisOrder::Xyz);
        assert!(AxisOrder::parse("yxz").unwrap_err().to_string().starts_with("order is \"yxz\""));
        assert!(ZPositive::parse("Down").unwrap_err().to_string().starts_with("z_positive"));
        let o = stored_origin([1.0, 2.0, 1000.0], [25.0, 25.0, 4.0], 11, ZPositive::Down);
        assert_eq!(o, [1.0, 2.0, -1040.0]);
        assert_eq!(stored_origin([1.0, 2.0, 3.0], [1.0; 3], 11, ZPositive::Up), [1.0, 2.0, 3.0]);
        let e = check_grid([0.0; 3], [25.0, 25.0, -4.0], ZPositive::Up).unwrap_err().to_string();
        assert!(e.starts_with("spacing: component 2 is -4") || e.starts_with("component 2 is -4"), "{e}");
        assert!(e.contains("z_positive=\"down\""), "{e}");
        assert!(check_grid([0.0, f64::NAN, 0.0], [1.0; 3], ZPositive::Down)
            .unwrap_err()
            .to_string()
            .contains("component 1"));
    }
}

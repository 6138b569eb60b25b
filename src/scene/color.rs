//! Colour by data: an object is drawn in one flat colour, or coloured through a colour map by its
//! own z or by a scalar given per sample / vertex / cell (`values=`).
//!
//! The contract:
//! * a colour map is 256 RGB entries in [0, 1] (a user's table of 2..=4096 entries is resampled
//!   to 256 by linear interpolation; built-in names are matplotlib's tables, see [`builtin_names`]);
//! * a scalar `s` maps to entry `min(floor(256 t), 255)` with `t = (s - lo) / (hi - lo)` clamped to
//!   [0, 1]: `lo` gives the first entry, `hi` the last, below and above clamp (matplotlib's
//!   `Normalize` and 256-entry colour maps, as PyVista draws them);
//! * NaN scalars (holes of `values`, no-data cells) get the NaN colour, by default
//!   [`DEFAULT_NAN_COLOR`] (mid grey, matplotlib's and PyVista's "bad" default is transparent, which
//!   an opaque occluder cannot be);
//! * `clim = None` is the data's own range (finite values only; a constant or all-NaN field gets
//!   `lo - 0.5 .. lo + 0.5`, resp. `0 .. 1`).
//!
//! `z` colouring uses the object's world z as drawn, before vertical exaggeration and without
//! the object's later translations (a horizon keeps its colours when moved).

use super::cmaps::BUILTIN;
use crate::error::{ensure, input_err, Result};

/// Entries of every colour map on the GPU.
pub const LUT_SIZE: usize = 256;

/// The colour of NaN scalars unless given: mid grey.
pub const DEFAULT_NAN_COLOR: [f32; 3] = [0.5, 0.5, 0.5];

/// The colour map used when a colour map is needed and none is given.
pub const DEFAULT_CMAP: &str = "viridis";

/// What an object is coloured by.
#[derive(Clone, Debug, PartialEq)]
pub enum ColorSource {
    /// The object's own world z (before exaggeration, without translations).
    Z,
    /// The per-vertex scalar stored in its tiles (`TileMesh::values`).
    Values,
}

/// A colour map as the user gave it: a name or a table.
#[derive(Clone, Debug)]
pub enum CmapArg {
    Name(String),
    /// (n, 3) RGB rows in [0, 1], 2 <= n <= 4096, and the map's name if it has one.
    Table(Vec<[f64; 3]>, Option<String>),
}

/// How a new object is coloured (the add functions' `color_by`, `values`, `cmap`, `clim`,
/// `nan_color`). `values` are per sample (height fields: (ny, nx) row-major) or per vertex
/// (meshes); grids carry theirs per cell.
#[derive(Clone, Debug)]
pub struct ColorByArg {
    pub source: ColorSource,
    pub values: Option<Vec<f64>>,
    pub cmap: Option<CmapArg>,
    pub clim: Option<[f64; 2]>,
    pub nan_color: Option<[f64; 3]>,
}

impl ColorByArg {
    /// Colour by z with the default map and range.
    pub fn z() -> Self {
        Self { source: ColorSource::Z, values: None, cmap: None, clim: None, nan_color: None }
    }
    /// Colour by `values` with the default map and range.
    pub fn values(values: Vec<f64>) -> Self {
        Self { source: ColorSource::Values, values: Some(values), cmap: None, clim: None, nan_color: None }
    }
}

/// An object's validated colouring.
#[derive(Clone, Debug, PartialEq)]
pub struct ColorBy {
    pub source: ColorSource,
    /// The colour map's name, or "custom" for a table.
    pub cmap: String,
    pub lut: Vec<[f32; 3]>,
    /// The scalar range: z in world units for [`ColorSource::Z`].
    pub clim: [f64; 2],
    pub nan_color: [f32; 3],
}

/// Names of the built-in colour maps.
pub fn builtin_names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(n, _)| *n).collect()
}

/// A built-in colour map by name (case-sensitive, as matplotlib's).
pub fn builtin(name: &str) -> Option<Vec<[f32; 3]>> {
    BUILTIN.iter().find(|(n, _)| *n == name).map(|(_, b)| {
        b.chunks_exact(3).map(|c| [c[0] as f32 / 255.0, c[1] as f32 / 255.0, c[2] as f32 / 255.0]).collect()
    })
}

/// `cmap` checked and resampled to [`LUT_SIZE`] entries: (name, table).
pub fn resolve_cmap(cmap: Option<&CmapArg>) -> Result<(String, Vec<[f32; 3]>)> {
    match cmap {
        None => Ok((DEFAULT_CMAP.into(), builtin(DEFAULT_CMAP).expect("default colour map is built in"))),
        Some(CmapArg::Name(n)) => builtin(n).map(|t| (n.clone(), t)).ok_or_else(|| {
            input_err(
                "cmap",
                format!(
                    "{n:?} is not a built-in colour map ({}); install matplotlib for its colour maps, or pass an (n, 3) \
                     table of RGB rows in [0, 1]",
                    builtin_names().join(", ")
                ),
            )
        }),
        Some(CmapArg::Table(t, name)) => {
            ensure((2..=4096).contains(&t.len()), "cmap", || {
                format!("the table has {} rows; expected 2..=4096 RGB rows", t.len())
            })?;
            for (i, row) in t.iter().enumerate() {
                for (a, v) in row.iter().enumerate() {
                    ensure(v.is_finite() && (0.0..=1.0).contains(v), "cmap", || {
                        format!("cmap[{i}, {a}] is {v}; colour map entries are RGB in [0, 1]")
                    })?;
                }
            }
            let n = t.len() - 1;
            let lut = (0..LUT_SIZE)
                .map(|k| {
                    let x = k as f64 * n as f64 / (LUT_SIZE - 1) as f64;
                    let i = (x.floor() as usize).min(n - 1);
                    let f = x - i as f64;
                    [0, 1, 2].map(|a| (t[i][a] * (1.0 - f) + t[i + 1][a] * f) as f32)
                })
                .collect();
            Ok((name.clone().unwrap_or_else(|| "custom".into()), lut))
        }
    }
}

/// The largest scalar magnitude drawn as itself: the lit pass receives scalars clamped to
/// ±`SCALAR_LIMIT` so that no data (`gpu::geometry::NO_DATA`, -3.4e38) interpolated with them
/// stays below -1e31 wherever its weight is above 3e-8 (a triangle touching no data is no data to
/// its corners); colour ranges lie within it.
pub const SCALAR_LIMIT: f64 = 1e30;

/// The colour range: `clim` checked, or the finite range of `data` (see the module's contract),
/// within ±[`SCALAR_LIMIT`].
pub fn resolve_clim(clim: Option<[f64; 2]>, data: impl Iterator<Item = f64>) -> Result<[f64; 2]> {
    if let Some([lo, hi]) = clim {
        ensure(lo.is_finite() && hi.is_finite() && lo < hi, "clim", || {
            format!("clim is ({lo}, {hi}); expected two finite numbers lo < hi")
        })?;
        ensure(lo.abs().max(hi.abs()) <= SCALAR_LIMIT, "clim", || {
            format!("clim is ({lo}, {hi}); colour ranges lie within ±1e30")
        })?;
        return Ok([lo, hi]);
    }
    let (lo, hi) = data
        .filter(|v| v.is_finite())
        .map(|v| v.clamp(-SCALAR_LIMIT, SCALAR_LIMIT))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    Ok(if lo > hi {
        [0.0, 1.0]
    } else if lo == hi {
        [lo - 0.5, lo + 0.5]
    } else {
        [lo, hi]
    })
}

/// A checked RGB colour in [0, 1] for `arg`.
pub fn check_rgb(c: [f64; 3], arg: &str) -> Result<[f32; 3]> {
    for (i, v) in c.iter().enumerate() {
        ensure(v.is_finite() && (0.0..=1.0).contains(v), arg, || {
            format!("component {i} is {v}; colours are (r, g, b) in [0, 1]")
        })?;
    }
    Ok(c.map(|v| v as f32))
}

impl ColorByArg {
    /// Validates everything but the data range: (source, cmap name, table, nan colour).
    pub(super) fn check(&self, n_expected: Option<(usize, &str)>) -> Result<()> {
        match (&self.source, &self.values, n_expected) {
            (ColorSource::Values, None, _) => {
                return Err(input_err("values", "color_by=\"values\" needs values"));
            }
            (ColorSource::Values, Some(v), Some((n, shape))) => {
                ensure(v.len() == n, "values", || format!("values has {} entries; expected {shape}", v.len()))?;
                for (k, x) in v.iter().enumerate() {
                    ensure(!x.is_infinite(), "values", || {
                        format!("values[{k}] (flat index) is {x}; use NaN for no data")
                    })?;
                }
            }
            (ColorSource::Z, Some(_), _) => {
                return Err(input_err("values", "values were given with color_by=\"z\"; pass one or the other"));
            }
            _ => {}
        }
        Ok(())
    }

    /// The validated colouring, with `data` the scalars `clim = None` takes its range from.
    pub(super) fn resolve(&self, data: impl Iterator<Item = f64>) -> Result<ColorBy> {
        let (cmap, lut) = resolve_cmap(self.cmap.as_ref())?;
        let nan_color = match self.nan_color {
            Some(c) => check_rgb(c, "nan_color")?,
            None => DEFAULT_NAN_COLOR,
        };
        let clim = resolve_clim(self.clim, data)?;
        Ok(ColorBy { source: self.source.clone(), cmap, lut, clim, nan_color })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_are_whole_and_named() {
        for n in builtin_names() {
            let t = builtin(n).unwrap();
            assert_eq!(t.len(), LUT_SIZE);
        }
        // viridis runs from dark purple to yellow (matplotlib's ends).
        let v = builtin("viridis").unwrap();
        assert_eq!(v[0].map(|c| (c * 255.0).round() as u8), [68, 1, 84]);
        assert_eq!(v[255].map(|c| (c * 255.0).round() as u8), [253, 231, 37]);
        let e = resolve_cmap(Some(&CmapArg::Name("nope".into()))).unwrap_err().to_string();
        assert!(e.starts_with("cmap") && e.contains("viridis"), "{e}");
    }

    #[test]
    fn tables_resample_linearly_and_are_checked() {
        let (_, t) = resolve_cmap(Some(&CmapArg::Table(vec![[0.0, 0.0, 0.0], [1.0, 0.5, 0.0]], None))).unwrap();
        assert_eq!(t.len(), LUT_SIZE);
        assert_eq!(t[0], [0.0, 0.0, 0.0]);
        assert_eq!(t[255], [1.0, 0.5, 0.0]);
        assert!((t[51][0] - 0.2).abs() < 1e-6);
        let e = resolve_cmap(Some(&CmapArg::Table(vec![[0.0, 2.0, 0.0], [1.0, 0.5, 0.0]], None))).unwrap_err();
        assert!(e.to_string().starts_with("cmap[0, 1]"), "{e}");
        assert!(resolve_cmap(Some(&CmapArg::Table(vec![[0.0; 3]], None))).is_err());
    }

    #[test]
    fn clim_defaults_to_the_finite_range() {
        assert_eq!(resolve_clim(None, [3.0, f64::NAN, -1.0].into_iter()).unwrap(), [-1.0, 3.0]);
        assert_eq!(resolve_clim(None, [2.0, 2.0].into_iter()).unwrap(), [1.5, 2.5]);
        assert_eq!(resolve_clim(None, [f64::NAN].into_iter()).unwrap(), [0.0, 1.0]);
        assert_eq!(resolve_clim(Some([0.0, 5.0]), [9.0].into_iter()).unwrap(), [0.0, 5.0]);
        for bad in [[1.0, 1.0], [2.0, 1.0], [f64::NAN, 1.0]] {
            assert!(resolve_clim(Some(bad), std::iter::empty()).unwrap_err().to_string().starts_with("clim"));
        }
    }
}

//! The error type of the core. The Python layer maps each variant onto geocull's exception hierarchy
//! (`InputError` for bad arguments, `DeviceError` for adapter/driver trouble).

/// Everything that can go wrong in geocull, as values (the core never panics on bad input).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad argument. `arg` names the argument as the caller spelled it.
    #[error("{}", if msg.starts_with(arg.as_str()) { msg.clone() } else { format!("{arg}: {msg}") })]
    Input { arg: String, msg: String },
    /// No usable GPU adapter, or the driver rejected the work.
    #[error("{0}")]
    Device(String),
}

pub type Result<T> = std::result::Result<T, Error>;

/// A number for a message: plain where that is short, scientific (`1e300`) where it is not.
pub fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// Shorthand for an [`Error::Input`] naming `arg`.
pub fn input_err(arg: impl Into<String>, msg: impl Into<String>) -> Error {
    Error::Input { arg: arg.into(), msg: msg.into() }
}

/// Returns `Err(Error::Input)` unless `cond` holds.
pub fn ensure(cond: bool, arg: &str, msg: impl FnOnce() -> String) -> Result<()> {
    if cond {
        Ok(())
    } else {
        Err(input_err(arg, msg()))
    }
}

/// An integer argument `v` as a count in `lo..=hi` (bindings pass Python ints as i64, so range
/// checks live here with the other value checks).
pub fn int_in(v: i64, arg: &str, lo: i64, hi: i64) -> Result<usize> {
    ensure((lo..=hi).contains(&v), arg, || format!("{v} is outside {lo}..{hi}"))?;
    Ok(v as usize)
}

/// An object id (ids are u32; anything else names no object).
pub fn object_id(v: i64) -> Result<u32> {
    u32::try_from(v).map_err(|_| input_err("id", format!("no object with id {v} in this scene")))
}

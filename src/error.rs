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

//! geocull: occlusion-culled rendering of geoscience sub-surface scenes.
//!
//! The pure-Rust core: a [`scene::Scene`] of tiled objects with LOD levels ([`lod`]), an f64
//! [`camera::Camera`], and a wgpu [`gpu::Renderer`] that draws a scene with one of the culling
//! strategies in [`cull`]. The Python bindings live in `python` (feature `python`) and only convert
//! arrays and errors.

pub mod camera;
pub mod cull;
pub mod error;
pub mod gpu;
pub mod iso;
pub mod lod;
pub mod scene;

#[cfg(feature = "python")]
mod python;

pub use camera::{Camera, Projection};
pub use cull::Culling;
pub use error::{Error, Result};
pub use gpu::{RenderOptions, RenderOutput, Renderer};
pub use scene::Scene;

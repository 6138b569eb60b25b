//! geocull: occlusion-culled rendering of geoscience sub-surface scenes.
//!
//! The pure-Rust core: a [`scene::Scene`] of tiled objects with LOD levels ([`lod`]), an f64
//! [`camera::Camera`], and a [`render::Renderer`] that draws a scene as a pipeline of named stages
//! (upload → strategy → draw → read-back) with one of the culling strategies in [`cull`], on the
//! wgpu mechanics of [`gpu`]; isosurfaces of volumes in [`iso`]. The Python bindings live in
//! `python` (feature `python`) and only convert arrays and errors.
//!
//! Dependency rule (checked by `scripts/check_layers.py` in CI):
//! `python → render → {cull, iso} → gpu → {scene, lod, camera, error}`; nothing imports upward.

pub mod camera;
pub mod cull;
pub mod error;
pub mod gpu;
pub mod grid;
pub mod iso;
pub mod lod;
pub mod render;
pub mod scene;

#[cfg(feature = "python")]
mod python;

/// Deterministic random numbers for unit tests (no rand dependency): a 64-bit LCG.
#[cfg(test)]
pub(crate) struct TestRng(pub u64);

#[cfg(test)]
impl TestRng {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.0
    }
    /// Uniform in [0, 1) with 53 bits.
    pub(crate) fn f(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(crate) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.f()
    }
    /// Uniform integer in a..=b.
    pub(crate) fn irange(&mut self, a: usize, b: usize) -> usize {
        a + ((self.next_u64() >> 33) as usize) % (b - a + 1)
    }
}

pub use camera::{Camera, Projection};
pub use error::{Error, Result};
pub use render::{RenderOptions, RenderOutput, Renderer};
pub use scene::Scene;

//! geocull: occlusion-culled rendering of geoscience sub-surface scenes.
//!
//! The pure-Rust core: a [`Scene`] of tiled objects with levels of detail, an f64 [`Camera`], and
//! a [`Renderer`] that draws a scene as a pipeline of named stages (upload → strategy → draw →
//! read-back) with one of the culling strategies ([`culling_modes`]); isosurfaces of a [`Volume`]
//! by an [`IsoRenderer`]. The modules are private: this page's re-exports are the crate's public
//! surface. The Python bindings live in `python` (feature `python`) and only convert arrays and
//! errors.
//!
//! Dependency rule (checked by `scripts/check_layers.py` in CI):
//! `python → render → {cull, iso} → gpu → {scene, lod, camera, error}`; nothing imports upward.

mod camera;
mod cull;
mod error;
mod gpu;
mod grid;
mod iso;
mod lod;
mod render;
mod scene;

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

// The public surface: what a Rust user builds, renders and reads a scene with. The modules are
// private; their items are public only within the crate (and to the bindings in `python`).
pub use camera::{Camera, Lens, Orbit, Projection};
pub use cull::{CullOptions, Stat, DEFAULT_CACHE_BUDGET};
pub use error::{Error, Interrupt, Result};
pub use iso::mesh::{isosurface_mesh, isosurface_mesh_sampled, IsoMesh};
pub use iso::render::{IsoCulling, IsoOptions, IsoOutput, IsoRenderer, IsoStats, IsoWalk};
pub use iso::scene_object::SceneIsosurface;
pub use iso::{BrickCache, BrickSource, MinMaxOctree, Volume};
pub use render::{Background, GridLod, Lod, RenderOptions, RenderOutput, RenderStats, Renderer};
pub use scene::color::{builtin_names as colormap_names, DEFAULT_CMAP, DEFAULT_NAN_COLOR};
pub use scene::grid::GridInfo;
pub use scene::lens::LensSlice;
pub use scene::{
    AddOptions, CmapArg, ColorBy, ColorByArg, ColorSource, GridFrame, HeightfieldInfo, Object, Scene, MAX_PRIORITY,
    PRIORITY_DEPTH_STEP,
};

/// The object kinds' registry ([`Object::kind`]): each kind's name and what is decided by it.
pub mod kinds {
    pub use crate::scene::kinds::{of, Kind, KINDS};
}

/// How a user's 3-D array maps onto a [`Volume`]: index order and a z axis growing up or down.
pub mod layout {
    pub use crate::iso::layout::{check_grid, stored_origin, AxisOrder, ZPositive};
}

/// The culling modes, by name (`RenderOptions::culling`), in the registry's order.
pub fn culling_modes() -> Vec<&'static str> {
    cull::names()
}

//! GPU mechanics, knowing no culling strategy: the device ([`GpuContext`]), render targets,
//! the scene's geometry buffers ([`SceneGeometry`]), the passes a frame is built from
//! ([`Passes`]: prepass, histogram, select, lit draw; one WGSL file each under `shaders/`),
//! named GPU timestamps and read-back (depth through a shader, [`depth_read`], since GL cannot
//! copy depth textures into buffers). Which tiles a pass draws is decided in `crate::cull`;
//! the order of a frame lives in `crate::render`.

mod box_early;
mod cell_values;
mod context;
pub mod depth_read;
pub mod geometry;
pub mod layout;
pub mod occluder_depth;
pub mod passes;
pub mod readback;
pub mod shader;
pub mod slab_test;
pub mod targets;
pub mod timing;

pub use context::GpuContext;
pub use geometry::SceneGeometry;
pub use layout::{ColorTables, DrawArgs, Globals, GpuObject};
pub use passes::Passes;
pub use readback::{map_err, ReadbackTexture};
pub use targets::Targets;
#[cfg(test)]
pub use targets::BACKGROUND;
pub use timing::Timestamps;

#[cfg(test)]
mod tests;

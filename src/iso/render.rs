//! GPU side of implicit occluders (placeholder; filled in by the isosurface work).
pub struct IsoGpu;

//! `culling="none"`: every fine tile of every visible object: the reference image.

use super::{CullStrategy, Draw, FrameInputs, Pixels, Visible};
use crate::error::Result;

pub struct NoCulling;

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(NoCulling)
}

impl CullStrategy for NoCulling {
    fn name(&self) -> &'static str {
        "none"
    }
    fn visible_set(&mut self, _frame: &FrameInputs<'_>, _enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        Ok(Visible::new(Draw::All, Pixels::FinalImage))
    }
}

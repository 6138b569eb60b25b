//! `culling="oracle"`: exactly the tiles that have at least one visible pixel in the unculled
//! image. It renders that image first, in `prepare` (not part of the frame time), counts the
//! pixels of each tile in it, then draws those tiles only: the lower bound that benchmarks
//! compare the practical strategies with.

use super::{CullStrategy, Draw, FrameInputs, Pixels, Visible};
use crate::error::Result;
use crate::gpu::{passes, readback};

#[derive(Default)]
pub struct Oracle {
    /// Visible pixels per tile in the reference image of the frame being rendered.
    reference: Vec<u32>,
}

pub fn make() -> Box<dyn CullStrategy> {
    Box::new(Oracle::default())
}

impl CullStrategy for Oracle {
    fn name(&self) -> &'static str {
        "oracle"
    }

    fn prepare(&mut self, f: &FrameInputs<'_>) -> Result<()> {
        let d = &f.ctx.device;
        let n = f.n_tiles();
        let all = passes::args_buffer(d, "reference_args", &f.pick(f.draw_args, |_| true));
        let counts = passes::counts_buffer(d, n);
        let mut enc = f.ctx.encoder("oracle_reference");
        f.passes.record_draw(
            &mut enc,
            f.main_targets,
            f.scene_bg,
            f.geometry,
            &all,
            false,
            f.draw_runs,
            f.outside,
            f.pass_breaks,
            None,
        );
        f.passes.record_histogram(d, &mut enc, &f.main_targets.id, (f.width, f.height), &counts, None);
        let rb = readback::copy_buffer(d, &mut enc, &counts, 4 * n.max(1) as u64);
        f.ctx.queue.submit([enc.finish()]);
        readback::map_all([&rb]);
        f.ctx.wait()?;
        f.ctx.take_error()?;
        let mut c: Vec<u32> = readback::read_mapped(&rb)?;
        c.truncate(n);
        self.reference = c;
        Ok(())
    }

    fn visible_set(&mut self, _f: &FrameInputs<'_>, _enc: &mut wgpu::CommandEncoder) -> Result<Visible> {
        let counts = std::mem::take(&mut self.reference);
        let mask = counts.iter().map(|&c| c > 0).collect();
        Ok(Visible::new(Draw::Mask(mask), Pixels::Host(counts)))
    }
}

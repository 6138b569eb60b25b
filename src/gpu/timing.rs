//! GPU timestamps by name: each pass asks for a span under a stats name ("prepass_ms",
//! "count_ms", "draw_ms", ...); spans of the same name add up. Absent (None) where the adapter
//! has no TIMESTAMP_QUERY.

use super::readback;
use crate::error::Result;
use std::sync::Mutex;

/// Pairs of timestamps a frame can hold.
const MAX_SPANS: u32 = 16;

pub struct Timestamps {
    set: wgpu::QuerySet,
    names: Mutex<Vec<&'static str>>,
}

impl Timestamps {
    pub fn new(d: &wgpu::Device) -> Self {
        let set = d.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: 2 * MAX_SPANS,
        });
        Self { set, names: Mutex::new(Vec::new()) }
    }

    /// Forgets the spans of the last frame.
    pub fn begin_frame(&mut self) {
        self.names.get_mut().unwrap_or_else(|e| e.into_inner()).clear();
    }

    fn next(&self, name: &'static str) -> Option<u32> {
        let mut n = self.names.lock().unwrap_or_else(|e| e.into_inner());
        (n.len() < MAX_SPANS as usize).then(|| {
            n.push(name);
            2 * (n.len() as u32 - 1)
        })
    }

    /// Timestamp writes for a render pass timed as `name` (None once all spans are taken).
    pub fn render(&self, name: &'static str) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.next(name).map(|i| wgpu::RenderPassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        })
    }

    /// Timestamp writes for a compute pass timed as `name`.
    pub fn compute(&self, name: &'static str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.next(name).map(|i| wgpu::ComputePassTimestampWrites {
            query_set: &self.set,
            beginning_of_pass_write_index: Some(i),
            end_of_pass_write_index: Some(i + 1),
        })
    }

    /// Records the resolve of this frame's spans; returns the buffer to copy back, if any.
    pub fn resolve(&self, d: &wgpu::Device, enc: &mut wgpu::CommandEncoder) -> Option<wgpu::Buffer> {
        let n = 2 * self.names.lock().unwrap_or_else(|e| e.into_inner()).len() as u32;
        (n > 0).then(|| {
            let b = d.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamps"),
                size: 8 * n as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            enc.resolve_query_set(&self.set, 0..n, &b, 0);
            readback::copy_buffer(d, enc, &b, 8 * n as u64)
        })
    }

    /// Milliseconds per name from the mapped read-back buffer (spans of one name summed).
    pub fn read(&self, mapped: &wgpu::Buffer, period_ns: f32) -> Result<Vec<(&'static str, f64)>> {
        let t: Vec<u64> = readback::read_mapped(mapped)?;
        let period = period_ns as f64 * 1e-6;
        let mut out: Vec<(&'static str, f64)> = Vec::new();
        for (k, &name) in self.names.lock().unwrap_or_else(|e| e.into_inner()).iter().enumerate() {
            let (a, b) = (t[2 * k], t[2 * k + 1]);
            let ms = if b > a { (b - a) as f64 * period } else { 0.0 };
            match out.iter_mut().find(|(n, _)| *n == name) {
                Some((_, v)) => *v += ms,
                None => out.push((name, ms)),
            }
        }
        Ok(out)
    }
}

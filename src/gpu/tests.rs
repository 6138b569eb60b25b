//! Tests of the GPU mechanics on inputs whose answer is known by construction (lavapipe on
//! machines without a GPU).

use super::passes::{args_buffer, counts_buffer, empty_args_buffer};
use super::*;
use crate::error::Error;

#[test]
fn scenes_larger_than_a_buffer_get_a_clear_error() {
    assert!(check_buffer_sizes(100, 300, 1 << 20).is_ok());
    let e = check_buffer_sizes(100_000, 300, 1 << 20).unwrap_err();
    assert!(matches!(e, Error::Device(ref m) if m.contains("too large")), "{e}");
    assert!(check_buffer_sizes(10, (u32::MAX as u64) + 1, u64::MAX).is_err());
}

fn device() -> Option<(GpuContext, Passes)> {
    let ctx = GpuContext::new("auto", wgpu::Features::empty()).ok()?;
    let p = Passes::new(&ctx.device);
    Some((ctx, p))
}

fn read_u32s(ctx: &GpuContext, enc: wgpu::CommandEncoder, src: &wgpu::Buffer, n: usize) -> Vec<u32> {
    let mut enc = enc;
    let rb = readback::copy_buffer(&ctx.device, &mut enc, src, 4 * n as u64);
    ctx.queue.submit([enc.finish()]);
    readback::map_all([&rb]);
    ctx.wait().unwrap();
    readback::read_mapped(&rb).unwrap()
}

/// An id image with a known number of pixels per id (runs crossing the 16-wide workgroups,
/// a partial last workgroup) is counted exactly.
#[test]
fn histogram_counts_every_pixel_once() {
    let Some((ctx, p)) = device() else { return };
    let (w, h) = (37u32, 5u32);
    let ids: Vec<u32> = (0..w * h).map(|i| if i % 7 == 0 { 0 } else { 1 + (i / 3) % 4 }).collect();
    let mut want = [0u32; 4];
    for &i in &ids {
        if i > 0 {
            want[i as usize - 1] += 1;
        }
    }
    let tex = targets::texture(
        &ctx.device,
        "ids",
        w,
        h,
        targets::ID_FORMAT,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    );
    ctx.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture: &tex,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: Default::default(),
        },
        bytemuck::cast_slice(&ids),
        wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * w), rows_per_image: Some(h) },
        wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
    );
    let counts = counts_buffer(&ctx.device, 4);
    let mut enc = ctx.encoder("test");
    enc.clear_buffer(&counts, 0, None);
    p.record_histogram(&ctx.device, &mut enc, &tex.create_view(&Default::default()), (w, h), &counts, None);
    assert_eq!(read_u32s(&ctx, enc, &counts, 4), want);
}

/// Draws whose count is at or below the threshold are switched off, the others copied as they are.
#[test]
fn select_switches_off_draws_at_or_below_the_threshold() {
    let Some((ctx, p)) = device() else { return };
    let d = &ctx.device;
    let n = 70; // more than one workgroup of 64
    let src: Vec<DrawArgs> = (0..n as u32)
        .map(|i| DrawArgs {
            index_count: 3 * (i + 1),
            instance_count: 1,
            first_index: i,
            base_vertex: 0,
            first_instance: i,
        })
        .collect();
    let counts: Vec<u32> = (0..n as u32).map(|i| i % 5).collect();
    let counts_buf = wgpu::util::DeviceExt::create_buffer_init(
        d,
        &wgpu::util::BufferInitDescriptor {
            label: None,
            contents: bytemuck::cast_slice(&counts),
            usage: wgpu::BufferUsages::STORAGE,
        },
    );
    let out = empty_args_buffer(d, "out", n);
    let mut enc = ctx.encoder("test");
    p.record_select(d, &mut enc, &counts_buf, &args_buffer(d, "src", &src), &out, n, 2.0, None);
    let got: Vec<u32> = read_u32s(&ctx, enc, &out, 5 * n);
    let got: &[DrawArgs] = bytemuck::cast_slice(&got);
    for i in 0..n {
        let want = if counts[i] <= 2 { src[i].off() } else { src[i] };
        assert_eq!(got[i], want, "draw {i}");
    }
}

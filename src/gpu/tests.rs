//! Tests of the GPU mechanics on inputs whose answer is known by construction (lavapipe on
//! machines without a GPU).

use super::geometry::check_buffer_sizes;
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
/// Contexts asking for the same backend and features share one device and its per-device
/// objects while any of them lives; after the last is gone the next one opens a new device.
#[test]
fn contexts_share_a_device_while_one_lives() {
    // Optional features no other test asks for: a device of this test's own.
    let mine = wgpu::Features::DEPTH32FLOAT_STENCIL8;
    let Ok(a) = GpuContext::new("auto", mine) else { return };
    let b = GpuContext::new("auto", mine).unwrap();
    assert_eq!(a.device_serial(), b.device_serial());
    let (pa, pb) = (a.per_device(Passes::new), b.per_device(Passes::new));
    assert!(std::sync::Arc::ptr_eq(&pa, &pb));
    let other = GpuContext::new("auto", mine | wgpu::Features::SHADER_EARLY_DEPTH_TEST).unwrap();
    assert_ne!(other.device_serial(), a.device_serial(), "other features, another device");
    let first = a.device_serial();
    drop((a, b, pa, pb));
    let c = GpuContext::new("auto", mine).unwrap();
    assert_ne!(c.device_serial(), first, "the last user gone, the device was closed");
}

#[test]
fn histogram_counts_every_pixel_once() {
    let Some((ctx, p)) = device() else { return };
    // Rows shorter than a workgroup's 8 x 16 pixels, and several workgroups with partial ones.
    for (w, h) in [(37u32, 5u32), (300, 19)] {
        histogram_case(&ctx, &p, w, h);
    }
}

fn histogram_case(ctx: &GpuContext, p: &Passes, w: u32, h: u32) {
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
    assert_eq!(read_u32s(ctx, enc, &counts, 4), want);
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

/// The depth read through a shader equals the texture bit for bit: a known pattern written with
/// `frag_depth`, an odd size (partial workgroups), whole and split into bands of rows.
#[test]
fn depth_is_read_back_exactly_whole_and_in_bands() {
    let Some((ctx, _)) = device() else { return };
    let d = &ctx.device;
    let (w, h) = (37u32, 150u32);
    let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING;
    let tex = targets::texture(d, "depth", w, h, targets::DEPTH_FORMAT, usage);
    let view = tex.create_view(&Default::default());
    // Texel (x, y) gets (x + y * 37) / 8192, exact in f32 and below 1.
    let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: None,
        source: wgpu::ShaderSource::Wgsl(
            "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
                 let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;
                 return vec4<f32>(p, 0.5, 1.0);
             }
             struct F { @builtin(frag_depth) z: f32 }
             @fragment fn fs(@builtin(position) c: vec4<f32>) -> F {
                 return F(f32(u32(c.x) + u32(c.y) * 37u) / 8192.0);
             }"
            .into(),
        ),
    });
    let pipeline = d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: None,
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: targets::DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    });
    let want: Vec<f32> = (0..w * h).map(|k| k as f32 / 8192.0).collect();
    // max_binding: the whole image in one band, then bands of 64 rows (64 + 64 + 22).
    for max_binding in [u64::MAX, 4 * w as u64 * 100] {
        let mut enc = ctx.encoder("test");
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: None,
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(0.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline);
            pass.draw(0..3, 0..1);
        }
        let rb = depth_read::DepthReader::new(d).record(d, &mut enc, &view, (w, h), max_binding);
        ctx.queue.submit([enc.finish()]);
        readback::map_all([rb.buffer()]);
        ctx.wait().unwrap();
        ctx.take_error().unwrap();
        let got = rb.read().unwrap();
        let bad = got.iter().zip(&want).position(|(a, b)| a.to_bits() != b.to_bits());
        assert!(
            bad.is_none(),
            "max_binding {max_binding}: texel {bad:?}: {} != {}",
            got[bad.unwrap()],
            want[bad.unwrap()]
        );
    }
    assert_eq!(depth_read::band_rows(37, 150, 4 * 37 * 100), 64);
    assert_eq!(depth_read::band_rows(37, 150, 4 * 37 * 150), 150);
    assert_eq!(depth_read::band_rows(16384, 16384, 128 << 20), 2048);
}

/// Cost of reading depth back, shader vs copy (where the adapter can copy depth), 1280 × 1024:
/// `cargo test --release depth_read_cost -- --ignored --nocapture`. Wall time of record + submit +
/// wait + map of one depth texture, median of 30.
#[test]
#[ignore]
fn depth_read_cost() {
    let Some((ctx, _)) = device() else { return };
    let d = &ctx.device;
    let (w, h) = (1280u32, 1024u32);
    let usage =
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC;
    let tex = targets::texture(d, "depth", w, h, targets::DEPTH_FORMAT, usage);
    let view = tex.create_view(&Default::default());
    let median = |f: &dyn Fn() -> wgpu::Buffer| {
        let mut t: Vec<f64> = (0..30)
            .map(|_| {
                let t0 = std::time::Instant::now();
                let b = f();
                readback::map_all([&b]);
                ctx.wait().unwrap();
                drop(b.slice(..).get_mapped_range());
                t0.elapsed().as_secs_f64() * 1e3
            })
            .collect();
        t.sort_by(f64::total_cmp);
        t[15]
    };
    let (view, reader) = (&view, depth_read::DepthReader::new(d));
    let shader = median(&|| {
        let mut enc = ctx.encoder("t");
        let rb = reader.record(d, &mut enc, view, (w, h), ctx.limits.max_storage_buffer_binding_size);
        ctx.queue.submit([enc.finish()]);
        rb.buffer().clone()
    });
    println!("{}: depth read through the shader: {shader:.2} ms", ctx.adapter_description());
    if ctx.depth_copies {
        let copy = median(&|| {
            let mut enc = ctx.encoder("t");
            let rb = ctx.read_depth(&mut enc, &tex);
            ctx.queue.submit([enc.finish()]);
            rb.buffer().clone()
        });
        println!("{}: depth copied to a buffer: {copy:.2} ms", ctx.adapter_description());
    }
}

/// Beyond 65,535 workgroups of 64 (4,194,240 tiles) the selection dispatches in 2-D and still
/// handles every tile.
#[test]
fn select_handles_more_tiles_than_one_dispatch_dimension() {
    let Some((ctx, p)) = device() else { return };
    let d = &ctx.device;
    let n = 65_535 * 64 + 1000;
    assert_eq!(passes::tile_groups(n), (65_535, 2));
    let src: Vec<DrawArgs> = (0..n as u32)
        .map(|i| DrawArgs { index_count: 3, instance_count: 1, first_index: 0, base_vertex: 0, first_instance: i })
        .collect();
    let counts: Vec<u32> = (0..n as u32).map(|i| i % 2).collect();
    let counts_buf = passes::counts_buffer_init(d, &counts);
    let out = empty_args_buffer(d, "out", n);
    let mut enc = ctx.encoder("test");
    p.record_select(d, &mut enc, &counts_buf, &args_buffer(d, "src", &src), &out, n, 0.0, None);
    let got: Vec<u32> = read_u32s(&ctx, enc, &out, 5 * n);
    let got: &[DrawArgs] = bytemuck::cast_slice(&got);
    for i in [0, 1, 4_194_239, 4_194_240, 4_194_241, n - 1] {
        assert_eq!(got[i].instance_count, (i % 2) as u32, "draw {i}");
        assert_eq!(got[i].first_instance, i as u32, "draw {i}");
    }
}

/// A vertical lattice of `nu` × `nv` samples at x = `x` with values varying along it.
fn lattice(nu: usize, nv: usize, x: f64) -> (Vec<[f64; 3]>, Vec<f64>) {
    let pos = (0..nu * nv).map(|k| [x, (k % nu) as f64, -((k / nu) as f64)]).collect();
    let vals = (0..nu * nv).map(|k| ((k * 7) % 5) as f64 + x).collect();
    (pos, vals)
}

/// A lattice replaced by one of the same layout is rewritten in place (the boxes become the new
/// one's); one of another size is not, nor is a scene where an object was added.
#[test]
fn a_replaced_lattice_of_the_same_layout_is_patched_and_another_is_not() {
    use crate::scene::{AddOptions, Scene};
    let Some((ctx, _)) = device() else { return };
    let mut s = Scene::new();
    let add = |s: &mut Scene, (nu, nv): (usize, usize), x: f64| {
        let (p, v) = lattice(nu, nv, x);
        s.add_lattice(&p, v, (nu, nv), "slice", AddOptions::new(16.0)).unwrap()
    };
    let id = add(&mut s, (6, 4), 0.0);
    let mut g = SceneGeometry::upload(&ctx, &s).unwrap();
    let w = add(&mut s, (6, 4), 5.0);
    s.replace_lattice(id, w).unwrap();
    let ids = s.replaced_since(g.key.1).unwrap();
    assert_eq!(ids, vec![id]);
    assert!(g.patch(&ctx, &s, &ids).unwrap());
    assert_eq!(g.key, s.geometry_key());
    let fresh = SceneGeometry::upload(&ctx, &s).unwrap();
    assert_eq!(g.bbox, fresh.bbox);
    assert_eq!(g.sub_boxes, fresh.sub_boxes);
    assert_eq!((g.fine.clone(), g.coarse.clone()), (fresh.fine.clone(), fresh.coarse.clone()));
    assert_eq!(s.replaced_since(s.geometry_key().1), Some(vec![]));
    // Another size: left as it was, for a full upload.
    let w = add(&mut s, (7, 4), 0.0);
    s.replace_lattice(id, w).unwrap();
    let before = g.key;
    assert!(!g.patch(&ctx, &s, &s.replaced_since(before.1).unwrap()).unwrap());
    assert_eq!(g.key, before);
    // An object added (and not replacing one) is no replacement.
    let k = s.geometry_key().1;
    add(&mut s, (6, 4), 9.0);
    assert_eq!(s.replaced_since(k), None);
}

#[test]
fn pass_breaks_bound_each_pass_by_its_triangles() {
    use super::passes::pass_breaks;
    // Index counts of five tiles: 3, 3, 1, 4 and 0 triangles.
    let tiles = [9u32, 9, 3, 12, 0];
    assert!(pass_breaks(tiles, None).is_empty());
    assert!(pass_breaks(tiles, Some(11)).is_empty(), "everything fits one pass");
    assert_eq!(pass_breaks(tiles, Some(6)), vec![2], "3 + 3, then 1 + 4 + 0 (5 <= 6)");
    assert_eq!(pass_breaks(tiles, Some(4)), vec![1, 3], "3 | 3 + 1 | 4 + 0");
    // A tile over the bound gets a pass of its own, and no pass is empty.
    assert_eq!(pass_breaks(tiles, Some(1)), vec![1, 2, 3], "each non-empty tile alone; the empty one joins the last");
    assert_eq!(pass_breaks([30u32, 3], Some(2)), vec![1]);
    assert!(pass_breaks([0u32; 4], Some(1)).is_empty());
}

//! Embedding sdfc in your own wgpu program: compile a scene, draw it with your own
//! device, queue and command encoder into your own texture, and save it as a PNG.
//! sdfc creates no instance here, installs no error handler and never waits on the
//! queue; this program does all of that itself.
//!
//! `cargo run --release --example embed -- examples/capsule.sdf capsule.png [320x240]`
//! draws what `sdfc render examples/capsule.sdf --size 320x240` draws. With
//! `--multiscale` last, the module has the multi-scale atlas pass, which the host runs
//! before the draw (`SceneRenderer::prepare`), as `sdfc render --multiscale on` does.

use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().collect();
    let multiscale = args.last().is_some_and(|a| a == "--multiscale");
    if multiscale {
        args.pop();
    }
    let (Some(scene), Some(out)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: embed SCENE OUT.png [WIDTHxHEIGHT] [--multiscale]");
        std::process::exit(2);
    };
    // 1. Check and compile the scene (the textures it reads are decoded for the GPU).
    let source = std::fs::read_to_string(scene)?;
    let analysis = sdfc::check(&source, Path::new(scene).parent());
    if analysis.has_errors() {
        eprint!(
            "{}",
            sdfc::diagnostic::render(scene, &source, &analysis.diagnostics, false)
        );
        std::process::exit(1);
    }
    let options = sdfc::Options {
        walk: sdfc::WalkForm::Loop,
        multiscale,
        ..Default::default()
    };
    let module = sdfc::compile(&analysis, &options)?.module;
    let textures = sdfc::Textures::load(&analysis.program)?;
    let mut view = sdfc::View::of(&analysis, None)?;
    if let Some((w, h)) = args.get(3).and_then(|s| s.split_once('x')) {
        (view.width, view.height) = (w.parse()?, h.parse()?);
    }

    // 2. The host's own wgpu: instance, adapter, device, queue.
    let instance = wgpu::Instance::default();
    let adapter = pollster::block_on(instance.request_adapter(&Default::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&Default::default()))?;

    // 3. The scene's pipeline on that device, and the globals from the scene's view.
    let format = wgpu::TextureFormat::Rgba8UnormSrgb;
    let mut scene = sdfc::SceneRenderer::new(&device, &queue, &module, &textures, format)?;
    scene.set_globals(&queue, &sdfc::globals(&view, sdfc::ViewMode::Color));

    // 4. Draw into the host's texture with the host's encoder, and read it back.
    let (width, height) = (view.width, view.height);
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("frame"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let row = (4 * width).div_ceil(256) * 256;
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (row * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    // The multi-scale pass, where the module has it: before the draw, in this encoder.
    scene.prepare(&device, &mut encoder, (width, height))?;
    {
        let view = target.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        scene.draw(&mut pass);
    }
    encoder.copy_texture_to_buffer(
        target.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(height),
            },
        },
        target.size(),
    );
    queue.submit([encoder.finish()]);
    readback
        .slice(..)
        .map_async(wgpu::MapMode::Read, |r| r.expect("the readback maps"));
    device.poll(wgpu::PollType::wait_indefinitely())?;
    let data = readback
        .slice(..)
        .get_mapped_range()
        .expect("the readback is mapped");
    let mut pixels = Vec::with_capacity((4 * width * height) as usize);
    for y in 0..height as usize {
        let start = y * row as usize;
        pixels.extend_from_slice(&data[start..start + 4 * width as usize]);
    }
    image::RgbaImage::from_raw(width, height, pixels)
        .ok_or("the frame has the wrong size")?
        .save(out)?;
    println!("{out}: {width}x{height}");
    Ok(())
}

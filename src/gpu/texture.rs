//! Images and samplers of the materials' textures.

use super::{Gpu, GpuError};
use crate::ir::texture::MipChain;
use std::path::Path;

/// Loads an image with its mip chain ([`MipChain`], the levels the CPU reference
/// samples), sRGB-decoded by the GPU when `srgb`.
pub fn load_texture(gpu: &Gpu, path: &Path, srgb: bool) -> Result<wgpu::Texture, GpuError> {
    let image = crate::ir::texture::decode(path).map_err(GpuError::Texture)?;
    upload(
        gpu,
        &MipChain::new(image),
        &path.display().to_string(),
        srgb,
    )
}

/// Uploads a mip chain as an `Rgba8UnormSrgb` (`srgb`) or `Rgba8Unorm` texture;
/// `name` is for messages.
pub fn upload(
    gpu: &Gpu,
    chain: &MipChain,
    name: &str,
    srgb: bool,
) -> Result<wgpu::Texture, GpuError> {
    let (w, h) = chain.levels[0].dimensions();
    let side = gpu.device.limits().max_texture_dimension_2d;
    if w > side || h > side || w == 0 || h == 0 {
        return Err(GpuError::Resource(format!(
            "texture {name} is {w}×{h}; this GPU's limit is {side} texels a side"
        )));
    }
    gpu.scoped(|| upload_to(&gpu.device, &gpu.queue, chain, srgb))
}

/// Creates the texture of a mip chain on `device` and queues its levels on `queue`
/// (no error scope, no wait: for a host's own device).
pub fn upload_to(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    chain: &MipChain,
    srgb: bool,
) -> wgpu::Texture {
    let (w, h) = chain.levels[0].dimensions();
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("image"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: chain.levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: if srgb {
            wgpu::TextureFormat::Rgba8UnormSrgb
        } else {
            wgpu::TextureFormat::Rgba8Unorm
        },
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (mip, level) in chain.levels.iter().enumerate() {
        let (lw, lh) = level.dimensions();
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            level,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * lw),
                rows_per_image: Some(lh),
            },
            wgpu::Extent3d {
                width: lw,
                height: lh,
                depth_or_array_layers: 1,
            },
        );
    }
    texture
}

/// The sampler of a texture's wrap mode (the manifest's `address_mode` and `filter`).
pub fn sampler(gpu: &Gpu, wrap: &str) -> wgpu::Sampler {
    sampler_on(&gpu.device, wrap)
}

/// [`sampler`] on a host's own device.
pub fn sampler_on(device: &wgpu::Device, wrap: &str) -> wgpu::Sampler {
    // One reading of the wrap modes for the GPU and the CPU reference.
    let mode = match crate::ir::texture::Wrap::parse(wrap) {
        crate::ir::texture::Wrap::Mirror => wgpu::AddressMode::MirrorRepeat,
        crate::ir::texture::Wrap::Clamp => wgpu::AddressMode::ClampToEdge,
        crate::ir::texture::Wrap::Repeat => wgpu::AddressMode::Repeat,
    };
    device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(wrap),
        address_mode_u: mode,
        address_mode_v: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

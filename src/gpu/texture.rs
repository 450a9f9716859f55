//! Images and samplers of the materials' textures.

use super::{Gpu, GpuError};
use std::path::Path;

/// Loads an image with an sRGB mip chain.
pub fn load_texture(gpu: &Gpu, path: &Path, srgb: bool) -> Result<wgpu::Texture, GpuError> {
    let unreadable = |e: &dyn std::fmt::Display| {
        GpuError::Texture(format!("cannot read texture {}: {e}", path.display()))
    };
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| unreadable(&e))?
        .with_guessed_format()
        .map_err(|e| unreadable(&e))?;
    // The header was checked at check time; these limits hold even if the file changed.
    reader.limits(crate::access::decoder_limits());
    let (w, h) = reader.into_dimensions().map_err(|e| unreadable(&e))?;
    let side = gpu.device.limits().max_texture_dimension_2d;
    if w > side || h > side {
        return Err(GpuError::Resource(format!(
            "texture {} is {w}×{h}; this GPU's limit is {side} texels a side",
            path.display()
        )));
    }
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| unreadable(&e))?
        .with_guessed_format()
        .map_err(|e| unreadable(&e))?;
    reader.limits(crate::access::decoder_limits());
    let img = reader.decode().map_err(|e| unreadable(&e))?.to_rgba8();
    let levels = 32 - w.max(h).max(1).leading_zeros();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("image"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: levels,
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
    let mut level = img;
    for mip in 0..levels {
        let (lw, lh) = level.dimensions();
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &level,
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
        level = image::imageops::resize(
            &level,
            (lw / 2).max(1),
            (lh / 2).max(1),
            image::imageops::FilterType::Triangle,
        );
    }
    Ok(texture)
}

pub fn sampler(gpu: &Gpu, wrap: &str) -> wgpu::Sampler {
    let mode = match wrap {
        "mirror" => wgpu::AddressMode::MirrorRepeat,
        "clamp" => wgpu::AddressMode::ClampToEdge,
        _ => wgpu::AddressMode::Repeat,
    };
    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(wrap),
        address_mode_u: mode,
        address_mode_v: mode,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: wgpu::MipmapFilterMode::Linear,
        ..Default::default()
    })
}

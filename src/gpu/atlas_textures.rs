//! The mesh renderer's textures: a baked atlas's images uploaded for sdfc's own lookup
//! (the whole atlas, one level), or for the standard filter as any glTF viewer reads
//! them: the material's images (a flat layout's level 0) with the box-filtered mip
//! chain a generic engine builds ([`generic_mips`]).

use super::Gpu;
use crate::asset::{ChartLayout, Textures};
use crate::codegen::mesh::MeshFilter;
use crate::ir::texture::MipChain;

/// The four textures (a black one for no emission) and the sampler, as `filter` reads
/// them: the whole atlas, or for the standard filter what other tools read (the glTF's
/// images: level 0's rows alone) with a generic chain.
pub(super) fn upload_textures(
    gpu: &Gpu,
    textures: &Textures,
    layout: &ChartLayout,
    filter: MeshFilter,
) -> ([wgpu::TextureView; 4], wgpu::Sampler) {
    let standard = filter == MeshFilter::Standard;
    let top = layout.image_height();
    let upload = |image: &image::RgbaImage, srgb: bool| {
        let cropped;
        let image = if standard && top < image.height() {
            cropped = image::imageops::crop_imm(image, 0, 0, image.width(), top).to_image();
            &cropped
        } else {
            image
        };
        upload_image(gpu, image, srgb, standard).create_view(&Default::default())
    };
    let black = image::RgbaImage::from_pixel(1, 1, image::Rgba([0, 0, 0, 255]));
    let views = [
        upload(&textures.base_color, true),
        upload(&textures.metallic_roughness, false),
        upload(&textures.normal, false),
        upload(textures.emissive.as_ref().unwrap_or(&black), true),
    ];
    let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("flat atlas"),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        mipmap_filter: if standard {
            wgpu::MipmapFilterMode::Linear
        } else {
            wgpu::MipmapFilterMode::Nearest
        },
        ..Default::default()
    });
    (views, sampler)
}

/// One image as a texture: level 0 alone, or with `chain` its generic mip chain too
/// (uploaded as the materials' textures are, [`super::texture::upload_to`]; the
/// renderer's error scope holds it).
fn upload_image(gpu: &Gpu, image: &image::RgbaImage, srgb: bool, chain: bool) -> wgpu::Texture {
    let mut levels = vec![image.clone()];
    if chain {
        levels.extend(generic_mips(image, srgb));
    }
    super::texture::upload_to(&gpu.device, &gpu.queue, &MipChain { levels }, srgb)
}

/// The mip chain a generic engine builds for `image` knowing nothing of its charts
/// (glGenerateMipmap's box filter): each level halves the last (sizes rounded down, at
/// least 1), a texel the mean of the 2 × 2 texels below it (of the last row or column
/// alone where a size was odd), in linear light for an sRGB image, down to 1 × 1.
/// Level 0 (the image) is not included.
pub fn generic_mips(image: &image::RgbaImage, srgb: bool) -> Vec<image::RgbaImage> {
    let decode = |x: u8, channel: usize| {
        let v = f32::from(x) / 255.0;
        if srgb && channel < 3 {
            crate::ir::texture::srgb_to_linear(f64::from(v)) as f32
        } else {
            v
        }
    };
    let encode = |v: f32, channel: usize| {
        if srgb && channel < 3 {
            crate::asset::srgb8(v)
        } else {
            crate::asset::unorm8(v)
        }
    };
    let mut out: Vec<image::RgbaImage> = Vec::new();
    let (mut w, mut h) = image.dimensions();
    while w > 1 || h > 1 {
        let above = out.last().unwrap_or(image);
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let level = image::RgbaImage::from_fn(nw, nh, |x, y| {
            let xs = [(2 * x).min(w - 1), (2 * x + 1).min(w - 1)];
            let ys = [(2 * y).min(h - 1), (2 * y + 1).min(h - 1)];
            let mut texel = [0u8; 4];
            for (c, t) in texel.iter_mut().enumerate() {
                let sum: f32 = ys
                    .iter()
                    .flat_map(|&yy| xs.iter().map(move |&xx| (xx, yy)))
                    .map(|(xx, yy)| decode(above.get_pixel(xx, yy)[c], c))
                    .sum();
                *t = encode(sum / 4.0, c);
            }
            image::Rgba(texel)
        });
        out.push(level);
        (w, h) = (nw, nh);
    }
    out
}

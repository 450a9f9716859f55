//! Export: the baked mesh and its atlas as files other programs read.
//!
//! - [`glb`] writes a binary glTF 2.0 file (`sdfc bake SCENE -o OUT.glb`): the mesh, one
//!   PBR material whose textures are the atlas's level 0 as PNGs (a flat layout's
//!   smaller levels are PNGs of their own, listed in the root's `extras.sdfc_levels`),
//!   and the atlas layout in the root's `extras.sdfc_atlas`; [`read_glb`] reads such a file back (`sdfc render
//!   OUT.glb`). See [`gltf`] for the file's structure.
//! - [`ktx2()`] writes the atlas's levels as an uncompressed KTX2 texture (see [`ktx2`]).
//!
//! Both writers check their input ([`check_mesh`], [`check_textures`],
//! [`check_layout`]) and refuse what would make an invalid file; the reader runs the
//! same checks, so what it returns is safe to index (every index in range, every chart
//! of every level inside the images).

pub mod gltf;
pub mod ktx2;

pub use self::gltf::{glb, read_glb, ReadError};
pub use self::ktx2::ktx2;

use super::{ChartLayout, FlatLayout, MeshData, Textures};

/// Checks that `mesh` is a non-empty triangle mesh: the four attributes have one value
/// per vertex, every value is finite, and the indices are whole triangles of existing
/// vertices.
pub fn check_mesh(mesh: &MeshData) -> Result<(), String> {
    let n = mesh.positions.len();
    if n == 0 || mesh.indices.is_empty() {
        return Err("the mesh is empty".into());
    }
    if n > u32::MAX as usize {
        return Err(format!("the mesh has too many vertices ({n})"));
    }
    for (what, len) in [
        ("normals", mesh.normals.len()),
        ("tangents", mesh.tangents.len()),
        ("texture coordinates", mesh.texcoords.len()),
    ] {
        if len != n {
            return Err(format!("the mesh has {n} positions but {len} {what}"));
        }
    }
    let finite = mesh.positions.iter().flatten().all(|x| x.is_finite())
        && mesh.normals.iter().flatten().all(|x| x.is_finite())
        && mesh.tangents.iter().flatten().all(|x| x.is_finite())
        && mesh.texcoords.iter().flatten().all(|x| x.is_finite());
    if !finite {
        return Err("the mesh has a non-finite vertex attribute".into());
    }
    if mesh.indices.len() % 3 != 0 {
        return Err(format!(
            "the mesh has {} indices, not whole triangles",
            mesh.indices.len()
        ));
    }
    if let Some(&i) = mesh.indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("the mesh's index {i} is past its {n} vertices"));
    }
    Ok(())
}

/// Checks that `layout` is usable: a power-of-two chart size, a non-empty grid, at
/// least one level and none with charts under 2 texels, and every chart of every level
/// inside the `width` × `height` image.
pub fn check_layout(layout: &FlatLayout) -> Result<(), String> {
    let FlatLayout {
        width,
        height,
        chart_size,
        columns,
        rows,
        ..
    } = *layout;
    if width == 0 || height == 0 || columns == 0 || rows == 0 {
        return Err("the atlas layout is empty".into());
    }
    if !chart_size.is_power_of_two() || !(2..=crate::asset::packed::MAX_SIDE).contains(&chart_size)
    {
        return Err(format!(
            "the atlas's chart size {chart_size} is not a power of two from 2 to {}",
            crate::asset::packed::MAX_SIDE
        ));
    }
    // The half-texel inset needs charts of at least 2 texels at every level.
    let levels = layout.levels();
    if levels == 0 || levels > chart_size.trailing_zeros() as usize {
        return Err(format!(
            "the atlas has {levels} levels for charts of {chart_size} texels"
        ));
    }
    if layout.gutter > chart_size {
        return Err(format!(
            "the atlas's gutter of {} texels is wider than its {chart_size}-texel charts",
            layout.gutter
        ));
    }
    for (level, &[x, y]) in layout.level_origins.iter().enumerate() {
        let n = layout.stride(level) as u64;
        if x as u64 + columns as u64 * n > width as u64
            || y as u64 + rows as u64 * n > height as u64
        {
            return Err(format!(
                "the atlas's level {level} does not fit in its {width}×{height} image"
            ));
        }
    }
    Ok(())
}

/// Checks that an atlas layout is usable ([`check_layout`], [`super::PackedLayout::check`]).
pub fn check_atlas(atlas: &ChartLayout) -> Result<(), String> {
    match atlas {
        ChartLayout::Flat(l) => check_layout(l),
        ChartLayout::Packed(l) => l.check(),
    }
}

/// Checks that every texture is the atlas's size, and that the emissive strength is a
/// finite number, 0 or more.
pub fn check_textures(textures: &Textures, layout: &ChartLayout) -> Result<(), String> {
    let images = [
        ("base colour", Some(&textures.base_color)),
        ("metallic-roughness", Some(&textures.metallic_roughness)),
        ("normal", Some(&textures.normal)),
        ("emissive", textures.emissive.as_ref()),
    ];
    for (what, image) in images {
        if let Some(image) = image {
            if image.dimensions() != (layout.width(), layout.height()) {
                return Err(format!(
                    "the {what} texture is {}×{}, the atlas {}×{}",
                    image.width(),
                    image.height(),
                    layout.width(),
                    layout.height()
                ));
            }
        }
    }
    textures.check_emissive_strength()
}

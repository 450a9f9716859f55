//! The one binding table of a generated module. It produces the WGSL declarations,
//! the manifest's `bindings` and, through [`Resource`], what the runtime binds at each
//! slot, so the three can never disagree.

use super::field::TextureUse;
use serde::Serialize;
use std::fmt::Write;

/// The kind of a binding, as the manifest names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    Uniform,
    StorageRead,
    StorageReadWrite,
    #[serde(rename = "texture-2d")]
    Texture2d,
    Sampler,
}

/// What is bound at a slot: the runtime's side of the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "resource", content = "index")]
pub enum Resource {
    /// The `Globals` uniform block (camera, light, view; see `GLOBALS_LAYOUT`).
    Globals,
    /// The image of `Manifest::textures[i]`.
    Texture(usize),
    /// The sampler of `Manifest::textures[i]` (its wrap mode).
    Sampler(usize),
    /// The compute grid's parameters (`GridParams`).
    GridParams,
    /// The compute points, read.
    Points,
    /// The compute results, written.
    Results,
    /// The unit normal at each compute point (`cs_material`), read.
    Normals,
    /// The module's constant tables (`Manifest::tables`), read.
    Tables,
    /// The run-time parameters' block (`Manifest::params`).
    Params,
    /// The screen tiles' leaf lists of the render's trace (`codegen::tiles`), which the
    /// runtime bins every frame (`gpu::tiles`).
    Tiles,
    /// The multi-scale atlas pass's coarse samples (`codegen::coarse`), which
    /// `cs_coarse` writes and the render entry points read, every frame (`gpu::coarse`).
    Coarse,
}

/// A resource binding of the generated module.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Binding {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub kind: Kind,
    /// WGSL type, or the image path for textures, or the wrap mode for samplers.
    pub detail: String,
    pub used_by: Vec<&'static str>,
    #[serde(skip)]
    pub resource: Resource,
}

/// The bind group of the render entry points and of the compute entry points.
pub const RENDER_GROUP: u32 = 0;
pub const COMPUTE_GROUP: u32 = 1;

/// The table for a module that samples `textures` and, with `tables`, reads the
/// `tables` storage buffer (`Manifest::tables`); with `tiles`, its render entry points
/// read the `tiles` buffer (`Options::tiles`); with `coarse`, the `coarse` buffer
/// (`Options::multiscale`).
pub fn table(
    textures: &[TextureUse],
    (tables, tiles, coarse): (bool, bool, bool),
    params: bool,
) -> Vec<Binding> {
    let fragment = || vec!["fs_main", "fs_aov", "cs_material", "cs_bake"];
    let mut out = vec![Binding {
        group: RENDER_GROUP,
        binding: 0,
        name: "globals".into(),
        kind: Kind::Uniform,
        detail: "Globals".into(),
        used_by: vec!["vs_main", "fs_main", "fs_aov"],
        resource: Resource::Globals,
    }];
    for (i, t) in textures.iter().enumerate() {
        let next = out.len() as u32;
        out.push(Binding {
            group: RENDER_GROUP,
            binding: next,
            name: format!("texture_{i}"),
            kind: Kind::Texture2d,
            detail: t.path.clone(),
            used_by: fragment(),
            resource: Resource::Texture(i),
        });
        out.push(Binding {
            group: RENDER_GROUP,
            binding: next + 1,
            name: format!("sampler_{i}"),
            kind: Kind::Sampler,
            detail: t.wrap.clone(),
            used_by: fragment(),
            resource: Resource::Sampler(i),
        });
    }
    // Every entry point that evaluates the scene may read these (until naga's
    // `Module::derive_users` says which do): the tables hold the shapes' groups and the
    // atlases (a displacement's height reads one from `scene_map`), the parameters
    // every run-time number.
    let scene = || {
        vec![
            "fs_main",
            "fs_aov",
            "cs_points",
            "cs_grid",
            "cs_atlas",
            "cs_material",
            "cs_bake",
        ]
    };
    let shared = [
        (
            tables,
            "tables",
            Kind::StorageRead,
            "array<u32>",
            Resource::Tables,
        ),
        (params, "params", Kind::Uniform, "Params", Resource::Params),
    ];
    for (wanted, name, kind, detail, resource) in shared {
        if wanted {
            out.push(Binding {
                group: RENDER_GROUP,
                binding: out.len() as u32,
                name: name.into(),
                kind,
                detail: detail.into(),
                used_by: scene(),
                resource,
            });
        }
    }
    if tiles {
        out.push(Binding {
            group: RENDER_GROUP,
            binding: out.len() as u32,
            name: "tiles".into(),
            kind: Kind::StorageRead,
            detail: "array<u32>".into(),
            used_by: vec!["fs_main", "fs_aov"],
            resource: Resource::Tiles,
        });
    }
    if coarse {
        out.push(Binding {
            group: RENDER_GROUP,
            binding: out.len() as u32,
            name: "coarse".into(),
            kind: Kind::StorageReadWrite,
            detail: "array<vec4<f32>>".into(),
            used_by: vec!["fs_main", "fs_aov", "cs_coarse"],
            resource: Resource::Coarse,
        });
    }
    let compute = [
        (
            "grid",
            Kind::Uniform,
            "GridParams",
            Resource::GridParams,
            vec!["cs_grid"],
        ),
        (
            "points",
            Kind::StorageRead,
            "array<vec4<f32>>",
            Resource::Points,
            vec!["cs_points", "cs_atlas", "cs_material", "cs_bake"],
        ),
        (
            "results",
            Kind::StorageReadWrite,
            "array<vec4<f32>>",
            Resource::Results,
            vec!["cs_points", "cs_grid", "cs_atlas", "cs_material", "cs_bake"],
        ),
        (
            "normals",
            Kind::StorageRead,
            "array<vec4<f32>>",
            Resource::Normals,
            vec!["cs_material"],
        ),
    ];
    for (binding, (name, kind, ty, resource, used_by)) in compute.into_iter().enumerate() {
        out.push(Binding {
            group: COMPUTE_GROUP,
            binding: binding as u32,
            name: name.into(),
            kind,
            detail: ty.into(),
            used_by,
            resource,
        });
    }
    out
}

/// The WGSL declarations of the table.
pub fn declarations(table: &[Binding]) -> String {
    let mut out = String::new();
    for b in table {
        let (space, ty) = match b.kind {
            Kind::Uniform => ("<uniform>", b.detail.as_str()),
            Kind::StorageRead => ("<storage, read>", b.detail.as_str()),
            Kind::StorageReadWrite => ("<storage, read_write>", b.detail.as_str()),
            Kind::Texture2d => ("", "texture_2d<f32>"),
            Kind::Sampler => ("", "sampler"),
        };
        let _ = writeln!(
            out,
            "@group({}) @binding({}) var{space} {}: {ty};",
            b.group, b.binding, b.name
        );
    }
    out
}

/// The header comment that documents the table.
pub fn describe(table: &[Binding]) -> String {
    let mut out = String::new();
    for b in table {
        let kind = serde_json::to_value(b.kind)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "//   @group({}) @binding({}) {kind} {}: {} (used by {})",
            b.group,
            b.binding,
            b.name,
            b.detail,
            b.used_by.join(", ")
        );
    }
    out
}

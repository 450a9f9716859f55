//! The scene's materials as `scene_material(id, p, n, footprint)`: one `case` per
//! material, each with the atlas samples its fields read (with the multi-scale pass,
//! rebuilt where the pass's samples agree: `codegen::coarse`).

use super::field::{field, Unsupported, Uses};
use super::{Definition, Generator, MaterialField, TextureUse};
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::sema::{FieldExpr, MaterialAttrs, MaterialDef, SurfaceInput, Ty, Value};
use std::fmt::Write;

impl Generator<'_> {
    /// `scene_material`: id 0 is the default; id i + 1 is `materials[i]`. Returns the
    /// textures the materials and heights sample (`uses` holds the heights').
    pub(super) fn materials(
        &mut self,
        materials: &[MaterialDef],
        mut uses: Uses,
    ) -> Result<Vec<TextureUse>, Vec<Diagnostic>> {
        let _ = writeln!(
            self.out,
            "// `footprint` is the pixel's size on the surface; tangent_u and tangent_v span the tangent plane.\nfn scene_material(id: i32, p: vec3<f32>, n: vec3<f32>, footprint: f32) -> Material {{\n    let tangent_u = normalize(select(cross(n, vec3<f32>(0.0, 0.0, 1.0)), cross(n, vec3<f32>(1.0, 0.0, 0.0)), abs(n.z) > 0.9));\n    let tangent_v = cross(n, tangent_u);\n    switch id {{"
        );
        let mut problems = Vec::new();
        for (i, m) in materials.iter().enumerate() {
            let start = self.out.len();
            let span = self.program.def(m.def).span;
            let case = i as i32 + 1;
            let body = self.material_body(&m.attrs, case, &mut uses, |what, e| {
                problems.push(Diagnostic::error(
                    codes::E_CODEGEN,
                    format!(
                        "cannot generate the {} of material `{}`: {}",
                        what.name(),
                        m.name,
                        e.0
                    ),
                    span,
                    "in this material",
                ))
            });
            let _ = writeln!(self.out, "        case {case}: {{\n{body}        }}");
            let read = uses.atlases.iter().map(|a| a.index()).collect();
            self.reads.by_material.push((case, read));
            self.reads
                .discrete
                .extend(uses.discrete.iter().map(|a| a.index()));
            let item_span = self.program.def(m.def).item_span;
            self.region(start, Some(item_span), Definition::Material(m.name.clone()));
        }
        // The default material's attributes are constants, which always generate.
        let body = self.material_body(&MaterialAttrs::default(), 0, &mut uses, |_, _| {});
        let _ = writeln!(
            self.out,
            "        default: {{\n{body}        }}\n    }}\n}}\n"
        );
        if problems.is_empty() {
            Ok(uses.textures)
        } else {
            Err(problems)
        }
    }

    /// The body of one `case` of `scene_material`: the atlas samples it needs and the
    /// `return`. An attribute that cannot be generated is reported to `problem`. `case`
    /// is the material's id (with the multi-scale pass, its atlas reads say it).
    fn material_body(
        &self,
        m: &MaterialAttrs,
        case: i32,
        uses: &mut Uses,
        mut problem: impl FnMut(MaterialField, Unsupported),
    ) -> String {
        uses.start_function();
        let mut attr = |v: &Value, what: MaterialField| {
            uses.srgb = what.is_color();
            field(v, uses).unwrap_or_else(|e| {
                problem(what, e);
                String::from("0.0")
            })
        };
        let color = match m.color.ty().base() {
            Ty::Vec(4) => format!("({}).rgb", attr(&m.color, MaterialField::Color)),
            Ty::Vec(3) => attr(&m.color, MaterialField::Color),
            _ => format!("vec3<f32>({})", attr(&m.color, MaterialField::Color)),
        };
        let r = attr(&m.roughness, MaterialField::Roughness);
        let mt = attr(&m.metallic, MaterialField::Metallic);
        let e = attr(&m.emission, MaterialField::Emission);
        // The surface normal is already unit; anything else is normalized.
        let normal = match &m.normal {
            Value::Field(e, _) if **e == FieldExpr::Input(SurfaceInput::Normal) => {
                String::from("n")
            }
            v => format!("sdfc_normalize_or({}, n)", attr(v, MaterialField::Normal)),
        };
        let samples: String = uses
            .atlases
            .iter()
            .map(|&k| match self.multiscale {
                true => format!(
                    "            let atlas_sample_{0} = atlas_{0}_pixel(p, {case});\n",
                    k.index()
                ),
                false => format!(
                    "            let atlas_sample_{0} = atlas_{0}_at(p, true);\n",
                    k.index()
                ),
            })
            .collect();
        let lets: String = uses
            .lets
            .iter()
            .map(|l| format!("            {l}\n"))
            .collect();
        format!("{samples}{lets}            return Material({color}, {r}, {mt}, {e}, {normal});\n")
    }
}

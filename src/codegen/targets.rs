//! The naga gate and naga's back ends: every module is parsed and validated
//! before it is used or written, and the other targets are translated from the
//! validated module.

use std::fmt;

crate::choice::choice_enum! {
/// An output language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Wgsl = "wgsl": "WGSL text, as validated.",
    Spirv = "spirv": "SPIR-V binary.",
    Glsl = "glsl": "GLSL for one entry point (`--entry`).",
    Msl = "msl": "Metal Shading Language.",
}
}

/// A module naga has parsed and validated.
pub struct Validated {
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
}

/// Why naga rejected WGSL: the message as naga renders it, with source context, and the
/// byte offset in the WGSL of naga's first label, when it gave one.
#[derive(Debug, Clone, PartialEq)]
pub struct NagaError {
    pub message: String,
    pub offset: Option<usize>,
}

impl fmt::Display for NagaError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.message)
    }
}

/// Validates a naga module (one sdfc built or transformed, so a failure is sdfc's).
fn revalidate(module: naga::Module) -> Result<Validated, String> {
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| e.into_inner().to_string())?;
    Ok(Validated { module, info })
}

/// The name of the temporary entry point that keeps the `sdf_NAME` functions alive
/// through compaction.
const KEEP: &str = "sdfc_keep_shape_functions";

/// The validated module with only what its entry points and its `sdf_NAME` functions
/// use (naga's compaction: the library's unused primitives, operators and types go),
/// validated again.
pub fn compact(v: &Validated) -> Result<Validated, String> {
    let mut module = v.module.clone();
    // A temporary entry point calls every sdf_NAME, so compaction keeps them; it is
    // removed after (entry points are a plain list: removing one moves no handle).
    let mut keep = naga::Function::default();
    for (h, f) in module.functions.iter() {
        if !f.name.as_deref().is_some_and(|n| n.starts_with("sdf_")) {
            continue;
        }
        let Some(arg) = f.arguments.first() else {
            continue;
        };
        let zero = keep
            .expressions
            .append(naga::Expression::ZeroValue(arg.ty), naga::Span::UNDEFINED);
        keep.body.push(
            naga::Statement::Call {
                function: h,
                arguments: vec![zero],
                result: None,
            },
            naga::Span::UNDEFINED,
        );
    }
    let Some(template) = module.entry_points.first() else {
        return Err(String::from("the module has no entry point"));
    };
    let mut ep = template.clone();
    ep.name = String::from(KEEP);
    ep.stage = naga::ShaderStage::Compute;
    ep.early_depth_test = None;
    ep.workgroup_size = [1, 1, 1];
    ep.workgroup_size_overrides = None;
    ep.mesh_info = None;
    ep.task_payload = None;
    ep.incoming_ray_payload = None;
    ep.function = keep;
    module.entry_points.push(ep);
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    module.entry_points.retain(|e| e.name != KEEP);
    revalidate(module)
}

/// Parses and validates WGSL with naga.
pub fn validate(wgsl: &str) -> Result<Validated, NagaError> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| NagaError {
        message: e.emit_to_string(wgsl),
        offset: e.location(wgsl).map(|l| l.offset as usize),
    })?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| NagaError {
        message: e.emit_to_string(wgsl),
        offset: e.location(wgsl).map(|l| l.offset as usize),
    })?;
    overridden(&module, &info, wgsl)?;
    Ok(Validated { module, info })
}

/// A module with pipeline-overridable constants (every module: `codegen::views`' view
/// mode and atlas AOV switch; with per-tile culling, `SCENE_CROWDED`) is also built as a
/// pipeline builds it: the views at their defaults, as a host that sets none (and naga's
/// other back ends) builds it, and the crowded tiles' paths off, as the runtime's first
/// pipeline (`gpu::render`). naga's pipeline-constant pass validates that form again,
/// and rejects some constructs the plain module passes (a constant matrix used on both
/// sides of an early return). One pass: the runtime's other variants differ only in the
/// constants' values, which fold the same expressions (measured: a second pass cost
/// 3 ms of `sdfc compile`'s 18 ms on `robot.sdf`).
fn overridden(
    module: &naga::Module,
    info: &naga::valid::ModuleInfo,
    wgsl: &str,
) -> Result<(), NagaError> {
    if module.overrides.is_empty() {
        return Ok(());
    }
    let crowded = super::tiles::CROWDED;
    let mut constants = naga::back::PipelineConstants::default();
    let mut said = String::from("the defaults");
    if module
        .overrides
        .iter()
        .any(|(_, o)| o.name.as_deref() == Some(crowded))
    {
        constants.insert(crowded.to_string(), 0.0);
        said = format!("{crowded} = false and the views' defaults");
    }
    naga::back::pipeline_constants::process_overrides(module, info, None, &constants)
        .map(|_| ())
        .map_err(|e| NagaError {
            message: format!("with {said}: {e:?}"),
            offset: match &e {
                naga::back::pipeline_constants::PipelineConstantError::ValidationError(v) => {
                    v.location(wgsl).map(|l| l.offset as usize)
                }
                _ => None,
            },
        })
}

/// Translated output: text, or SPIR-V bytes.
pub enum Output {
    Text(String),
    Binary(Vec<u8>),
}

/// Translates a validated module. GLSL holds one entry point per file, named by `entry`
/// (the caller checks it names one). WGSL is naga's rendering of the module, after
/// `header` (a comment).
pub fn translate(
    v: &Validated,
    header: &str,
    target: Target,
    entry: &str,
) -> Result<Output, String> {
    // naga's other back ends take no pipeline-overridable constants: they get the
    // module's defaults (the view read from the globals: `codegen::views`).
    let resolved;
    let v = if matches!(target, Target::Wgsl) || v.module.overrides.is_empty() {
        v
    } else {
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &v.module,
            &v.info,
            None,
            &naga::back::PipelineConstants::default(),
        )
        .map_err(|e| format!("the pipeline constants' defaults: {e:?}"))?;
        resolved = Validated {
            module: module.into_owned(),
            info: info.into_owned(),
        };
        &resolved
    };
    match target {
        Target::Wgsl => {
            let text = naga::back::wgsl::write_string(
                &v.module,
                &v.info,
                naga::back::wgsl::WriterFlags::empty(),
            )
            .map_err(|e| e.to_string())?;
            Ok(Output::Text(format!("{header}{text}")))
        }
        Target::Spirv => {
            let words = naga::back::spv::write_vec(
                &v.module,
                &v.info,
                &naga::back::spv::Options::default(),
                None,
            )
            .map_err(|e| e.to_string())?;
            Ok(Output::Binary(
                words.iter().flat_map(|w| w.to_le_bytes()).collect(),
            ))
        }
        Target::Msl => {
            let (text, _) = naga::back::msl::write_string(
                &v.module,
                &v.info,
                &naga::back::msl::Options {
                    // 1.2: the multi-scale pass's fragment stage reads a writable
                    // storage buffer, which MSL 1.0 and 1.1 do not allow.
                    lang_version: (1, 2),
                    ..Default::default()
                },
                &naga::back::msl::PipelineOptions::default(),
            )
            .map_err(|e| e.to_string())?;
            Ok(Output::Text(text))
        }
        Target::Glsl => {
            let ep = v
                .module
                .entry_points
                .iter()
                .find(|e| e.name == entry)
                .ok_or_else(|| {
                    let names: Vec<&str> = v
                        .module
                        .entry_points
                        .iter()
                        .map(|e| e.name.as_str())
                        .collect();
                    format!(
                        "no entry point `{entry}`; the module has: {}",
                        names.join(", ")
                    )
                })?;
            let options = naga::back::glsl::Options {
                version: naga::back::glsl::Version::Desktop(450),
                ..Default::default()
            };
            let pipeline = naga::back::glsl::PipelineOptions {
                shader_stage: ep.stage,
                entry_point: entry.to_string(),
                multiview: None,
            };
            let mut text = String::new();
            let mut writer = naga::back::glsl::Writer::new(
                &mut text,
                &v.module,
                &v.info,
                &options,
                &pipeline,
                naga::proc::BoundsCheckPolicies::default(),
            )
            .map_err(|e| e.to_string())?;
            writer.write().map_err(|e| e.to_string())?;
            Ok(Output::Text(text))
        }
    }
}

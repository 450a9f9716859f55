//! The naga gate and naga's back ends: every module is parsed and validated
//! before it is used or written, and the other targets are translated from the
//! validated module.

use std::fmt;

/// An output language.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Target {
    Wgsl,
    Spirv,
    Glsl,
    Msl,
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
    Ok(Validated { module, info })
}

/// Translated output: text, or SPIR-V bytes.
pub enum Output {
    Text(String),
    Binary(Vec<u8>),
}

/// Translates a validated module. GLSL holds one entry point per file, named by `entry`.
pub fn translate(v: &Validated, wgsl: &str, target: Target, entry: &str) -> Result<Output, String> {
    match target {
        Target::Wgsl => Ok(Output::Text(wgsl.to_string())),
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
                &naga::back::msl::Options::default(),
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

//! `--param NAME=VALUE` and `--time T`: the run-time parameters a command renders,
//! evaluates or bakes with. They reach the checker through `Access` (the CPU reference
//! and every compile-time consumer use them) and the GPU through the module's
//! parameter block (its defaults are these values); the WGSL does not change.

use std::sync::OnceLock;

/// The run-time parameters of `render`, `eval` and `bake`.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct ParamArgs {
    /// Set a run-time parameter (a `param` item) for this run: `--param radius=0.7`, or
    /// a vector's components with commas: `--param tint=0.8,0.3,0.2` (repeatable). The
    /// value must lie in the parameter's range.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub params: Vec<(String, Vec<f64>)>,
    /// The time in seconds the scene's `time` reads (default 0).
    #[arg(long, value_name = "T", value_parser = parse_time)]
    pub time: Option<f64>,
}

static SET: OnceLock<Vec<(String, Vec<f64>)>> = OnceLock::new();

impl ParamArgs {
    /// Records the values for the scenes this command loads (once, at start).
    pub fn install(&self) {
        let mut all = self.params.clone();
        if let Some(t) = self.time {
            all.push((String::from("time"), vec![t]));
        }
        let _ = SET.set(all);
    }
}

/// The values `--param` and `--time` set, if any.
pub fn set() -> &'static [(String, Vec<f64>)] {
    SET.get().map_or(&[], Vec::as_slice)
}

fn parse_param(s: &str) -> Result<(String, Vec<f64>), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("`{s}` is not NAME=VALUE"))?;
    let name = name.trim();
    if name.is_empty() {
        return Err(format!("`{s}` has no name before `=`"));
    }
    let value = value
        .split(',')
        .map(|c| {
            c.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("`{}` is not a finite number", c.trim()))
        })
        .collect::<Result<Vec<f64>, String>>()?;
    if value.len() > 4 {
        return Err(format!("`{s}` has {} components; at most 4", value.len()));
    }
    Ok((name.to_string(), value))
}

fn parse_time(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t.is_finite() && t >= 0.0 => Ok(t),
        _ => Err(format!(
            "`{s}` is not a time in seconds (a finite number ≥ 0)"
        )),
    }
}

/// Why the values set do not fit the checked scene's parameters: an unknown name (with
/// a did-you-mean), a vector of the wrong size, or a value outside the range.
pub fn validate(program: &sdfc::sema::Program) -> Result<(), String> {
    for (name, value) in set() {
        if name == "time" {
            continue;
        }
        let Some(p) = program
            .params
            .iter()
            .find(|p| &p.name == name && p.name != "time")
        else {
            let names: Vec<&str> = program
                .params
                .iter()
                .filter(|p| p.name != "time")
                .map(|p| p.name.as_str())
                .collect();
            let mut msg = format!("the scene has no parameter `{name}`");
            if let Some(best) = sdfc::sema::closest(name, names.iter().copied()) {
                msg.push_str(&format!(" (did you mean `{best}`?)"));
            } else if names.is_empty() {
                msg.push_str(" (it declares none)");
            } else {
                msg.push_str(&format!(" (it has {})", names.join(", ")));
            }
            return Err(msg);
        };
        if value.len() != p.size {
            return Err(format!(
                "`{name}` has {} component{}, the value {}",
                p.size,
                if p.size == 1 { "" } else { "s" },
                value.len()
            ));
        }
        if let Some(x) = value.iter().find(|x| **x < p.range.0 || **x > p.range.1) {
            return Err(format!(
                "{x} is outside the range of `{name}`, [{}, {}]",
                p.range.0, p.range.1
            ));
        }
    }
    Ok(())
}

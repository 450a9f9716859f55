//! `sdfc bench`'s measure of atlases on moving shapes: the time to recompute their
//! geometry on the CPU when a parameter changes (what a slider or a frame of `time`
//! costs before its upload), over values spread across each parameter's range.

use sdfc::Module;
use std::time::{Duration, Instant};

/// Values per parameter.
const STEPS: usize = 16;

/// The recomputation times (one per value of each parameter, the others at their
/// defaults); empty when the module has no atlas on a moving shape.
pub fn recompute_times(module: &Module) -> Vec<Duration> {
    if !module.has_moving_atlases() {
        return Vec::new();
    }
    let mut words = module.manifest.tables.clone();
    let mut times = Vec::new();
    for f in &module.manifest.params.fields {
        // `time` has no end: one period of a second is spread over.
        let hi = f.max.unwrap_or(f.min + 1.0);
        for i in 0..STEPS {
            let x = f.min + (hi - f.min) * i as f64 / (STEPS - 1) as f64;
            let value = vec![x; f.default.len()];
            let values = |n: &str| (n == f.name).then(|| value.clone());
            let t = Instant::now();
            // A value where a seed cannot be projected is measured all the same.
            let _ = module.write_tables_at(&values, &mut words);
            times.push(t.elapsed());
        }
    }
    times
}

/// The line `sdfc bench` prints, if the module has atlases on moving shapes.
pub fn line(module: &Module, times: &[Duration]) -> Option<String> {
    if times.is_empty() {
        return None;
    }
    let mut sorted = times.to_vec();
    sorted.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    Some(format!(
        "moving atlases: {} of them, recomputed on the CPU in {:.2} ms median, {:.2} ms at most ({} values over the parameters' ranges)",
        module.moving.len(),
        ms(sorted[sorted.len() / 2]),
        ms(sorted[sorted.len() - 1]),
        sorted.len()
    ))
}

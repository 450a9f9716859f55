//! The compile-time geometry of atlases as diagnostics on the scene's spans: seeds that
//! cannot be projected, moved far or jumped; seeds that coincide; merges whose seeds
//! cannot reach each other; cycles of merges with a topological obstruction.

use super::atlas::{scale, Atlas, PrepareError};
use super::merge::{self, Remedy, Unreachable, HOLONOMY_LIMIT_DEG, RESIDUAL_LIMIT};
use super::Status;
use crate::codes;
use crate::diagnostic::Diagnostic;
use crate::ir::texture::Textures;
use crate::ir::{self, eval};
use crate::sema::{AtlasDef, Program};
use glam::DVec3;
use std::sync::Arc;

/// The inputs [`Atlas::prepare`] reads, without spans: the shape's IR, the atlas's
/// name and settings, its seeds' names, positions and tangents, its merges.
fn prepare_key(def: &AtlasDef, shape: &ir::Shape) -> String {
    let seeds: Vec<_> = def
        .seeds
        .iter()
        .map(|s| (&s.name, s.position, s.tangent))
        .collect();
    let merges: Vec<_> = def.merges.iter().map(|m| (m.a, m.b)).collect();
    format!(
        "{:?}|{:?}|{seeds:?}|{merges:?}|{:?}",
        def.name, def.params, shape.nodes
    )
}

/// Prepared atlases by their inputs, so that an edit that leaves an atlas's inputs as
/// they were (a comment, formatting, another definition) does not redo its geometry
/// (the language server checks the document on every edit). Atlases on displaced
/// shapes, whose fields read other atlases and textures, are always prepared afresh.
static PREPARED: std::sync::Mutex<Vec<(String, Result<Atlas, PrepareError>)>> =
    std::sync::Mutex::new(Vec::new());

/// The most prepared atlases kept, most recently used last.
const PREPARED_KEPT: usize = 16;

/// How many preparations were answered from the cache, and how many were computed.
pub static PREPARE_STATS: [std::sync::atomic::AtomicUsize; 2] = [
    std::sync::atomic::AtomicUsize::new(0),
    std::sync::atomic::AtomicUsize::new(0),
];

fn prepare_cached(
    def: &AtlasDef,
    shape: &ir::Shape,
    heights: impl FnOnce() -> Arc<dyn ir::Heights>,
) -> Result<Atlas, PrepareError> {
    use std::sync::atomic::Ordering::Relaxed;
    if !shape.heights().is_empty() {
        return Atlas::prepare_in(def, shape, heights());
    }
    let key = prepare_key(def, shape);
    // A poisoned lock (a panic elsewhere while holding it) only loses the cache.
    let hit = PREPARED.lock().ok().and_then(|mut kept| {
        let at = kept.iter().position(|(k, _)| *k == key)?;
        let entry = kept.remove(at);
        let value = entry.1.clone();
        kept.push(entry);
        Some(value)
    });
    if let Some(value) = hit {
        PREPARE_STATS[0].fetch_add(1, Relaxed);
        return value;
    }
    PREPARE_STATS[1].fetch_add(1, Relaxed);
    let value = Atlas::prepare(def, shape);
    if let Ok(mut kept) = PREPARED.lock() {
        if kept.len() >= PREPARED_KEPT {
            drop(kept.remove(0));
        }
        kept.push((key, value.clone()));
    }
    value
}

/// What an atlas on a displaced shape evaluates its heights with: the environment
/// made of the atlases prepared before it and the program's textures (the CPU
/// reference layer's `reference::Env::shared`, which lies above this one).
pub type MakeHeights<'a> = &'a dyn Fn(&[Option<Atlas>], &Textures) -> Arc<dyn ir::Heights>;

/// Every atlas of a checked, error-free program prepared (None where it cannot be),
/// with the diagnostics of their geometry. `heights` makes the environment of an
/// atlas whose shape has displacements or shell maps.
pub fn prepare_all(
    program: &Program,
    heights: MakeHeights,
) -> (Vec<Option<Atlas>>, Vec<Diagnostic>) {
    let mut out = Vec::new();
    let mut diags = Vec::new();
    // What one evaluation of each atlas's shape costs, and one walk of the atlas: an
    // atlas on a displaced shape walks the height's atlas at every evaluation.
    let mut walks: Vec<f64> = Vec::new();
    // Atlases on displaced shapes evaluate their heights: those read textures (their
    // texels bound the heights) and the atlases prepared before them. A displaced
    // render target needs the textures to be lowered for its rest-pose query.
    let displaced = program
        .atlases
        .iter()
        .map(|d| &d.shape)
        .chain(program.render.as_ref().map(|r| &r.target))
        .any(|v| crate::sema::displaced(v).is_some());
    let textures = if displaced {
        Textures::load(program).unwrap_or_default()
    } else {
        Textures::default()
    };
    let target = program
        .render
        .as_ref()
        .and_then(|r| ir::lower_shape_textured(&r.target, &textures));
    for def in &program.atlases {
        let Some(shape) = ir::lower_shape_textured(&def.shape, &textures) else {
            out.push(None);
            walks.push(f64::INFINITY);
            continue;
        };
        // A height that reads an atlas declared later is not in the environment yet: the
        // CPU evaluates its band's bound, not a walk.
        let cost = shape.eval_cost(|k| walks.get(k.index()).copied().unwrap_or(1.0));
        walks.push(walk_evals(def) * cost);
        if !(cost <= MAX_EVAL_COST) {
            diags.push(cost_error(program, def, &shape, cost));
            out.push(None);
            continue;
        }
        match prepare_cached(def, &shape, || heights(&out, &textures)) {
            Ok(mut a) => {
                if let Some(t) = &target {
                    a.rest = ir::rest::RestQuery::find(t, &shape);
                    rest_pose(def, &a, program, &mut diags);
                }
                diags.extend(diagnostics(def, &a));
                out.push(Some(a));
            }
            Err(PrepareError::SeedOffSurface { seed }) => {
                diags.push(
                    Diagnostic::error(
                        codes::E_SEED_PROJECTION,
                        format!(
                            "seed `{}` cannot be projected onto the surface of atlas `{}`",
                            def.seeds[seed].name, def.name
                        ),
                        def.seeds[seed].position_span,
                        "projection does not converge here",
                    )
                    .with_note("seeds are moved onto the surface by Newton steps along the gradient; place this one nearer the shape"),
                );
                out.push(None);
            }
        }
    }
    (out, diags)
}

/// The most primitive evaluations one evaluation of an atlas's shape may cost
/// ([`ir::Shape::eval_cost`]): preparing an atlas evaluates its shape tens of
/// thousands of times. Two atlases of 20 steps with two seeds, the second on a shape
/// displaced by the first, cost about 1,000 and check in 0.1 s; a third on top costs
/// about 940,000 and never finished (over 120 s); an atlas on four shell maps stacked
/// on a displaced sphere costs about 170,000 and took 25 s (three: 24,000, 3.4 s).
pub const MAX_EVAL_COST: f64 = 50_000.0;

/// Field evaluations of one walk of an atlas, as the cost model counts them: N steps
/// (times 1 + refine), each a gradient and a step (8 evaluations), from up to 4 seeds.
fn walk_evals(def: &AtlasDef) -> f64 {
    let p = &def.params;
    p.steps as f64 * (1.0 + p.refine as f64) * 8.0 * def.seeds.len().clamp(1, 4) as f64
}

/// E0119 on an atlas whose shape costs more than [`MAX_EVAL_COST`] to evaluate, with
/// the atlases its heights walk and the displacements and shell maps that multiply.
fn cost_error(program: &Program, def: &AtlasDef, shape: &ir::Shape, cost: f64) -> Diagnostic {
    let mut d = Diagnostic::error(
        codes::E_WALK_NESTING,
        format!(
            "evaluating the shape of atlas `{}` costs about {} primitive evaluations, over the limit of {}",
            def.name,
            fmt_count(cost),
            fmt_count(MAX_EVAL_COST)
        ),
        def.shape_span,
        "each of this shape's evaluations is too costly to walk",
    );
    let mut walked = Vec::new();
    for h in shape.heights() {
        if let Some(j) = h.atlas.filter(|j| !walked.contains(j)) {
            walked.push(j);
            let inner = program.atlas(j);
            d = d.with_label(
                inner.shape_span,
                format!("every evaluation walks atlas `{}`", inner.name),
            );
        }
    }
    d.with_note(
        "a walk evaluates its shape at every step; each displacement or shell map \
         evaluates its base 7 times, and each height that reads an atlas walks it, so \
         stacked displacements and atlases on displaced shapes multiply",
    )
    .with_help(
        "stack fewer displacements and shell maps under the atlas, or read the base \
         shape's atlas in the height instead of an atlas on a displaced shape",
    )
}

/// A count for a message: 940000 → "940,000"; infinite → "unbounded".
fn fmt_count(x: f64) -> String {
    if !x.is_finite() || x >= 1e18 {
        return String::from("more than 10^18");
    }
    let digits = format!("{}", x.round() as u64);
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

pub fn fmt_point(p: DVec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// The diagnostics of one prepared atlas.
pub fn diagnostics(def: &AtlasDef, atlas: &Atlas) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    moved_seeds(def, atlas, &mut out);
    parallel_tangents(def, atlas, &mut out);
    coincident_seeds(def, atlas, &mut out);
    unreachable_merges(def, atlas, &mut out);
    obstructions(def, atlas, &mut out);
    mirrored_seeds(def, atlas, &mut out);
    out
}

/// Seeds on the negative side of the `mirror` plane: their side takes the uv of the
/// other, so they are never the nearest seed of any point.
fn mirrored_seeds(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    let Some(n) = atlas.mirror else { return };
    let tol = 1e-6 * scale(&atlas.shape);
    for (i, s) in atlas.seeds.iter().enumerate() {
        let side = s.seed.p.dot(n);
        if side < -tol {
            out.push(
                Diagnostic::warning(
                    codes::W_MIRRORED_SEED,
                    format!(
                        "seed `{}` of atlas `{}` is on the mirrored side of its `mirror` plane",
                        def.seeds[i].name, def.name
                    ),
                    def.seeds[i].position_span,
                    "this side takes the uv of its reflection, so this seed is never used",
                )
                .with_help(format!(
                    "place it on the other side, at {}, or remove it",
                    fmt_point(s.written - 2.0 * s.written.dot(n) * n)
                )),
            );
        }
    }
}

/// Where the render target uses the atlas's shape through `elongate` (no inverse) or in
/// more places than are followed.
fn rest_pose(def: &AtlasDef, atlas: &Atlas, program: &Program, out: &mut Vec<Diagnostic>) {
    let Some(render) = &program.render else {
        return;
    };
    let why = if atlas.rest.stretched {
        "through `elongate`, which has no inverse: the uv are constant across its stretched middle"
    } else if atlas.rest.truncated {
        "in more places than the rest-pose query follows; the others take the uv at the point itself"
    } else {
        return;
    };
    out.push(
        Diagnostic::warning(
            codes::W_NO_REST_POSE,
            format!("the render uses the shape of atlas `{}` {why}", def.name),
            render.target_span,
            "the render target",
        )
        .with_note(format!(
            "uv follow a warped shape by querying the atlas at the rest pose ω⁻¹(x) (§5.1); at most {} places are followed",
            ir::rest::MAX_OCCURRENCES
        )),
    );
}

/// Seeds that projection moved far (onto another part) or visibly (onto the surface).
fn moved_seeds(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    let s = scale(&atlas.shape);
    for (i, seed) in atlas.seeds.iter().enumerate() {
        let sd = &def.seeds[i];
        if seed.jumped(s) {
            out.push(
                Diagnostic::warning(
                    codes::W_SEED_JUMP,
                    format!(
                        "seed `{}` lands {:.3} away on another part of the surface",
                        sd.name, seed.moved
                    ),
                    sd.position_span,
                    format!("projected to {}", fmt_point(seed.seed.p)),
                )
                .with_note(format!(
                    "the surface is {:.3} from the written position, but projection moved the seed {:.3}",
                    seed.written_distance.abs(), seed.moved
                ))
                .with_help(format!(
                    "write the position on the part you mean, or `{}`",
                    fmt_vec(seed.seed.p)
                )),
            );
        } else if seed.moved > 1e-3 * s && !atlas.shape.is_dynamic() {
            // (On a moving shape the seeds move with it: where one lands is no news.)
            out.push(
                Diagnostic::note_diag(
                    codes::N_SEED_MOVED,
                    format!(
                        "seed `{}` is {:.3} off the surface and was moved onto it",
                        sd.name, seed.moved
                    ),
                    sd.position_span,
                    format!("projected to {}", fmt_point(seed.seed.p)),
                )
                .with_help(format!(
                    "write `{}` to place it on the surface",
                    fmt_vec(seed.seed.p)
                ))
                .with_fix(
                    "snap seed to surface",
                    sd.position_span,
                    fmt_vec(seed.seed.p),
                ),
            );
        }
    }
}

/// Seeds whose written `tangent` is (nearly) parallel to the surface normal, so it has no
/// direction in the tangent plane: the default frame is used instead, and said so.
fn parallel_tangents(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    for (sd, seed) in def.seeds.iter().zip(&atlas.seeds) {
        let (Some(_), Some(span), true) = (sd.tangent, sd.tangent_span, seed.default_tangent)
        else {
            continue;
        };
        let n = seed.seed.n;
        let axis = if n.x.abs() < 0.9 { "x" } else { "z" };
        out.push(
            Diagnostic::warning(
                codes::W_TANGENT_PARALLEL,
                format!(
                    "the tangent of seed `{}` is parallel to the surface normal there",
                    sd.name
                ),
                span,
                format!("parallel to the normal {}", fmt_point(n)),
            )
            .with_note(format!(
                "a tangent must point along the surface; the default frame was used: e1 is the \
                 world {axis} axis projected onto the tangent plane, {}",
                fmt_point(seed.seed.e1)
            ))
            .with_help("give a direction across the normal, or remove `tangent …`"),
        );
    }
}

/// Seeds that project to the same point as an earlier one.
fn coincident_seeds(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    for &(i, j) in &atlas.coincident {
        let mut d = Diagnostic::warning(
            codes::W_COINCIDENT_SEEDS,
            format!(
                "seeds `{}` and `{}` project to the same point",
                def.seeds[i].name, def.seeds[j].name
            ),
            def.seeds[j].span,
            format!("`{}` is never the nearest seed", def.seeds[j].name),
        )
        .with_label(
            def.seeds[i].span,
            format!("at {}", fmt_point(atlas.seeds[i].seed.p)),
        );
        if let Some(m) = def
            .merges
            .iter()
            .find(|m| (m.a, m.b) == (i, j) || (m.a, m.b) == (j, i))
        {
            d = d
                .with_label(m.span, "this merge is ignored")
                .with_note("a merge needs two seeds some distance apart");
        }
        out.push(d);
    }
}

/// Merges whose seeds no geodesic walk connects.
fn unreachable_merges(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    for u in &atlas.graph.unreachable {
        let m = &def.merges[u.merge];
        let (a, b) = (&def.seeds[u.a].name, &def.seeds[u.b].name);
        let reason = match u.status {
            Status::SharpFeature => format!("the walk meets a sharp feature at {}", fmt_point(u.at)),
            Status::TooFar => format!(
                "the seeds are farther apart than max_distance = {}",
                u.distance_limit
            ),
            Status::HeuristicFailed => format!(
                "the walk's Euclidean heuristic fails at {} (the direction to the seed is along the normal)",
                fmt_point(u.at)
            ),
            Status::NotReached => format!(
                "the walk ends {} away without reaching the seed",
                fmt_point(u.at)
            ),
            Status::Ok => String::from("the walk failed"),
        };
        out.push(
            Diagnostic::error(
                codes::E_UNREACHABLE_MERGE,
                format!("seeds `{a}` and `{b}` cannot be merged: {reason}"),
                m.span,
                format!("Alg. 1 from `{b}` to `{a}` fails ({})", u.status.name()),
            )
            .with_note("merged seeds need a geodesic walk between them, in at least one direction")
            .with_help(help(atlas, u)),
        );
    }
}

/// What fixes an unreachable merge: a setting under which the walk succeeds, tried at
/// compile time ([`merge::remedy`]), or else how to place the merge.
fn help(atlas: &Atlas, u: &Unreachable) -> String {
    let f = |q: DVec3| eval::distance(atlas.field(), q);
    let seeds: Vec<_> = atlas.seeds.iter().map(|s| s.seed).collect();
    let params = atlas.params.reference();
    match merge::remedy(&f, &seeds, u.a, u.b, u.status, &params) {
        Some(Remedy::Steps(n)) => format!(
            "with `steps = {n}` this merge is reachable: shorter steps follow the surface between the seeds"
        ),
        Some(Remedy::MaxDistance(d)) => {
            let d = format!("{d:.6}");
            let d = d.trim_end_matches('0').trim_end_matches('.');
            format!("with `max_distance = {d}` this merge is reachable")
        }
        Some(Remedy::SharpTolerance(t)) => format!(
            "with `sharp_tolerance = {t}` this merge is reachable, but walks then cross creases of that angle too; or merge seeds on the same side of the edge"
        ),
        None if u.status == Status::SharpFeature => String::from(
            "merge seeds on the same side of the edge: no number of steps up to 64 gets across",
        ),
        None if u.status == Status::TooFar => String::from("merge through a seed in between"),
        None => String::from(
            "merge through a seed in between: no number of steps up to 64 gets across",
        ),
    }
}

/// Merge cycles that cannot close into one chart.
fn obstructions(def: &AtlasDef, atlas: &Atlas, out: &mut Vec<Diagnostic>) {
    for c in atlas.graph.cycles.iter().filter(|c| c.is_obstruction()) {
        let edges: Vec<&crate::uv::merge::Edge> =
            c.edges.iter().map(|&k| &atlas.graph.edges[k]).collect();
        let mut names: Vec<&str> = c
            .seeds
            .iter()
            .map(|&i| def.seeds[i].name.as_str())
            .collect();
        names.push(names[0]);
        let closing = edges.last().expect("a cycle has edges");
        let mut d = Diagnostic::warning(
            codes::W_OBSTRUCTION,
            format!(
                "the merges around {} cannot close into one uv chart",
                names.join(" → ")
            ),
            def.merges[closing.merge].span,
            format!(
                "holonomy {:.1}°, offset residual {:.0}% of an edge",
                c.holonomy.to_degrees(),
                100.0 * c.residual
            ),
        );
        for e in &edges[..edges.len() - 1] {
            d = d.with_label(
                def.merges[e.merge].span,
                format!("residual {:.0}%", 100.0 * e.residual),
            );
        }
        d = d
            .with_note(format!(
                "around this cycle the transported frames turn by {:.1}° and the uv offsets miss by {:.0}% of the cycle's length; limits are {HOLONOMY_LIMIT_DEG}° and {:.0}% (a topological obstruction, e.g. seeds merged around a cylinder)",
                c.holonomy.to_degrees(),
                100.0 * c.closure,
                100.0 * RESIDUAL_LIMIT
            ))
            .with_help("leave one merge of the cycle out: its frontier becomes a seam");
        out.push(d);
    }
}

fn fmt_vec(p: DVec3) -> String {
    let t = |x: f64| {
        let s = format!("{x:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
        if s == "-0" {
            String::from("0")
        } else {
            s
        }
    };
    format!("[{}, {}, {}]", t(p.x), t(p.y), t(p.z))
}

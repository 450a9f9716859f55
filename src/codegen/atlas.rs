//! Atlas code: per atlas, its field, gradient, one Alg. 1 step, the walk (unrolled
//! to exactly N steps with N − i folded, or a rolled loop), the search for the
//! geodesic-nearest seed over the seed grid, and Alg. 2's blend with the merged
//! neighbours. Seeds (projected positions, solved frames and offsets), the merge
//! graph, σ and the grid are constants. The scene-independent pieces are in
//! `shaders/uv.wgsl`.

crate::choice::choice_enum! {
/// Whether the nearest-seed search uses the seed grid ([`SeedGrid`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeedGridChoice {
    #[default]
    Auto = "auto": "The grid for atlases of more than 4 seeds (the default).",
    On = "on": "The grid for every atlas.",
    Off = "off": "A plain scan of every seed.",
}
}

impl SeedGridChoice {
    pub fn grid(self, atlas: &Atlas) -> SeedGrid {
        let n = atlas.seeds.len();
        match self {
            SeedGridChoice::Off => SeedGrid::single(n),
            SeedGridChoice::Auto if n <= 4 => SeedGrid::single(n),
            _ => atlas.seed_grid(),
        }
    }
}

crate::choice::choice_enum! {
/// Where an atlas's seeds (positions, frames, offsets) and merge graph live.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SeedData {
    #[default]
    Auto = "auto": "Baked in for atlases of up to 64 seeds (AUTO_BAKED_SEEDS), in the buffer above (the default).",
    Baked = "baked": "Baked into the shader as `var<private>` arrays.",
    Buffer = "buffer": "In the `tables` storage buffer.",
}
}

/// The most seeds [`SeedData::Auto`] bakes in. Measured on lavapipe (docs/performance.md):
/// baked renders faster up to here (sphere.sdf 1.27×, robot.sdf's 42 seeds
/// 1.07×, plate.sdf's 64 seeds even); above, the buffer wins everything (a 1,200-sphere
/// city with 200 seeds: pipeline 1.74 → 0.99 s, frame 1.10 → 0.79 s, the language
/// server's full analysis p95 46 → 28 ms).
pub const AUTO_BAKED_SEEDS: usize = 64;

impl SeedData {
    /// Whether an atlas of `seeds` seeds has them in the buffer.
    pub fn in_buffer(self, seeds: usize) -> bool {
        match self {
            SeedData::Auto => seeds > AUTO_BAKED_SEEDS,
            SeedData::Baked => false,
            SeedData::Buffer => true,
        }
    }
}

use super::emit::{arg, lit, point_expr, vec3, Writer};
use super::moving::{adjacency, reserve, SeedsAt, SEED_WORDS};
use super::template;
use crate::uv::grid::SeedGrid;
use crate::uv::logmap::sharp_angle;
use crate::uv::prune;
use crate::uv::Atlas;
use glam::DVec3;

crate::choice::choice_enum! {
/// How the walk's N steps are emitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WalkForm {
    #[default]
    Unrolled = "unrolled": "N calls of the step, each with its constant N − i.",
    Loop = "loop": "A loop of N iterations.",
}
}

/// The WGSL of atlas `k`, from the template `shaders/atlas.wgsl.in`;
/// `atlas_NAME(p) -> AtlasSample` is its entry.
pub fn emit(
    k: usize,
    atlas: &Atlas,
    grid: &SeedGrid,
    options: &super::Options,
    words: &mut Vec<u32>,
    groups: &mut Vec<std::sync::Arc<crate::ir::group::Group>>,
    moving: Option<usize>,
) -> Result<(String, Option<SeedsAt>), template::Mismatch> {
    let (form, warm) = (options.walk, !options.cold);
    let p = &atlas.params;
    let mut w = Writer::new(&format!("atlas_{k}_f"));
    w.unions_as_code = options.unions_as_code;
    w.guard_cost = options.bounds.min_cost();
    // A moving atlas's seeds move: its walks are not pruned by where they lie.
    let pruning = (options.prune && !options.constant_uv && moving.is_none())
        .then(|| atlas.pruning())
        .flatten();
    let field_fn = field_fn(k, atlas, options, &mut w, pruning.as_ref(), words, groups);
    groups.append(&mut w.groups);
    let grad_value_fn = grad_value_fn(k, atlas, options);
    let (walk_begin, walk_end) = walk_mask(k, pruning.is_some());
    let n = p.steps.max(1);
    let walk_steps = walk_steps(k, n, form);
    let (refine_fns, refine_call) = refinement(k, n, p)?;
    let cells = grid.cells();
    // Outside the grid (or without one) the list is the full one; the grid's constants
    // are then unused, but must still be finite.
    let (grid_min, grid_inv, grid_dims) = if cells == 0 {
        (DVec3::ZERO, DVec3::ONE, [1; 3])
    } else {
        (grid.min, DVec3::ONE / grid.cell, grid.dims)
    };
    let (tables, at) = tables(
        k,
        atlas,
        grid,
        words,
        options.seed_data.in_buffer(atlas.seeds.len()),
        moving,
    );
    let sigma = match at.and_then(|a| a.sigma) {
        Some(_) => format!("bitcast<f32>(tables[ATLAS_{k}_SIGMA_AT])"),
        None => lit(atlas.sigma),
    };
    let values = [
        ("name", atlas.name.clone()),
        ("k", k.to_string()),
        ("seeds", atlas.seeds.len().to_string()),
        ("n", n.to_string()),
        ("field_fn", field_fn),
        ("field_helpers", w.helpers),
        ("grad_value_fn", grad_value_fn),
        ("walk_begin", walk_begin),
        ("walk_end", walk_end),
        ("h_gradient", lit(p.h_gradient)),
        ("onto_tolerance", lit(atlas.onto_tolerance())),
        ("reproject", p.reproject.to_string()),
        ("heuristic_tolerance", lit(p.heuristic_tolerance)),
        ("fd_gradient", lit(p.fd_gradient)),
        ("fd_start", lit(p.fd_start())),
        ("fd_curvature", lit(p.fd_curvature)),
        ("fd_floor", lit(p.fd_floor)),
        ("theta0", lit(sharp_angle(p.sharp_tolerance))),
        ("cells", cells.to_string()),
        ("tables", tables),
        (
            "walk_form",
            String::from(match form {
                WalkForm::Unrolled => "unrolled",
                WalkForm::Loop => "in a loop",
            }),
        ),
        ("walk_steps", walk_steps),
        ("refine_fns", refine_fns),
        ("refine_call", refine_call),
        ("min_reach", lit(p.min_reach)),
        ("grid_cells", cells.to_string()),
        ("grid_min", vec3(grid_min)),
        ("grid_inv_cell", vec3(grid_inv)),
        (
            "grid_dims",
            format!(
                "vec3<u32>({}u, {}u, {}u)",
                grid_dims[0], grid_dims[1], grid_dims[2]
            ),
        ),
        ("sigma", sigma),
        (
            "entry",
            if options.constant_uv {
                String::from("    // Constant (sdfc bench's baseline without walks).\n    return AtlasSample(vec2<f32>(0.5, 0.5), 0.5, 0.0, vec4<f32>(0.0, 0.0, 0.0, 1.0), 0.0, 1.0, vec3<f32>(1.0, 0.0, 0.0), vec3<f32>(0.0, 1.0, 0.0));\n")
            } else {
                entry(k, atlas)
            },
        ),
        ("warm", warm.to_string()),
        ("max_distance", lit(p.max_distance)),
    ];
    Ok((template::fill(template::ATLAS, &values)?, at))
}

/// The atlas's field function `atlas_K_f`, written with `w` (whose helpers go with it);
/// with the walks' pruning, also the whole field `atlas_K_whole` and the walk's mask.
fn field_fn(
    k: usize,
    atlas: &Atlas,
    options: &super::Options,
    w: &mut Writer,
    pruning: Option<&prune::Pruning>,
    words: &mut Vec<u32>,
    groups: &mut Vec<std::sync::Arc<crate::ir::group::Group>>,
) -> String {
    match pruning {
        None => {
            let field = w.shape(&atlas.shape, atlas.shape.root(), "p");
            format!(
                "fn atlas_{k}_f(p: vec3<f32>) -> f32 {{\n    sdf_evals = sdf_evals + 1u;\n{}    return {field}.x;\n}}\n",
                w.out
            )
        }
        Some(pr) => {
            // The whole field, for points outside the guard or the window.
            let mut whole = Writer::new(&format!("atlas_{k}_whole"));
            whole.unions_as_code = options.unions_as_code;
            whole.guard_cost = options.bounds.min_cost();
            let whole_result = whole.shape(&atlas.shape, atlas.shape.root(), "p");
            w.prune = Some((format!("atlas_{k}_mask"), std::sync::Arc::new(pr.clone())));
            w.indent(1);
            let field = w.shape(&atlas.shape, atlas.shape.root(), "p");
            w.helpers.push_str(&whole.helpers);
            groups.append(&mut whole.groups);
            let whole_fn = format!(
                "fn atlas_{k}_whole(p: vec3<f32>) -> f32 {{\n{}    return {whole_result}.x;\n}}\n\n",
                whole.out
            );
            whole_fn + &pruned_field(k, pr, &w.out, &field, words)
        }
    }
}

/// `atlas_K_grad_value(x, h) -> vec4<f32>`: the field's gradient at x (xyz) and f
/// there (w). Where the compiler differentiates the field forward
/// (`Params::exact_gradient`, `ir::dual`), exact (h unused), from `atlas_K_dual`: one
/// evaluation of the derivative instead of six of the field; else by central
/// differences of step h, with the mean of the six taps for f, f(x) + (h²/6)·Δf
/// (`uv/logmap.rs: gradient_value`). `Options::differences` keeps the differences (for
/// measuring the two; the CPU reference then differs by their error).
fn grad_value_fn(k: usize, atlas: &Atlas, options: &super::Options) -> String {
    if atlas.params.exact_gradient && !options.differences {
        let mut w = super::dual::DualWriter::new(&format!("atlas_{k}_dual"));
        let d = w.node(&atlas.shape, atlas.shape.root(), "p");
        return format!(
            "{}// The field's gradient and value by forward derivatives (codegen/dual.rs).
fn atlas_{k}_dual(p: vec3<f32>) -> vec4<f32> {{
    sdf_evals = sdf_evals + 1u;
{}    return {d};
}}

// The gradient at x (xyz) and f there (w), exact: h is the differences' step elsewhere.
fn atlas_{k}_grad_value(x: vec3<f32>, h: f32) -> vec4<f32> {{
    return atlas_{k}_dual(x);
}}
",
            w.helpers, w.out
        );
    }
    format!(
        "// The gradient by central differences of step h (xyz), with the mean of its six taps
// (w): f(x) + (h²/6)·Δf, f at x for no evaluation (uv/logmap.rs: gradient_value).
fn atlas_{k}_grad_value(x: vec3<f32>, h: f32) -> vec4<f32> {{
    let dx = vec3<f32>(h, 0.0, 0.0);
    let dy = vec3<f32>(0.0, h, 0.0);
    let dz = vec3<f32>(0.0, 0.0, h);
    let a = vec3<f32>(atlas_{k}_f(x + dx), atlas_{k}_f(x + dy), atlas_{k}_f(x + dz));
    let b = vec3<f32>(atlas_{k}_f(x - dx), atlas_{k}_f(x - dy), atlas_{k}_f(x - dz));
    let sum = a + b;
    return vec4<f32>((a - b) / (2.0 * h), (sum.x + sum.y + sum.z) / 6.0);
}}
"
    )
}

/// The lines that set and reset a pruned walk's mask around it (none unpruned).
fn walk_mask(k: usize, pruned: bool) -> (String, String) {
    if pruned {
        (
            format!("            atlas_{k}_centre = atlas_{k}_p(j);\n            atlas_{k}_reach = min(dmax, {} * length(x - atlas_{k}_centre));\n            atlas_{k}_mask = atlas_{k}_walk_mask(j, atlas_{k}_reach);\n", lit(prune::CHORD_REACH)),
            format!("            atlas_{k}_mask = 0xffffffffu;\n"),
        )
    } else {
        (String::new(), String::new())
    }
}

/// The walk's `n` steps: `n` calls, each with its constant N − i, or a loop.
fn walk_steps(k: usize, n: u32, form: WalkForm) -> String {
    match form {
        WalkForm::Unrolled => (0..n)
            .map(|i| {
                let remaining = lit((n - i) as f64);
                format!("    st = atlas_{k}_step(st, p, dmax, {remaining}, hmin);\n")
            })
            .collect::<String>(),
        WalkForm::Loop => format!(
            "    for (var i = 0u; i < {n}u; i = i + 1u) {{\n        st = atlas_{k}_step(st, p, dmax, f32({n}u - i), hmin);\n    }}\n"
        ),
    }
}

/// The refinement's functions and call, only where the atlas asks for it.
fn refinement(
    k: usize,
    n: u32,
    p: &crate::uv::Params,
) -> Result<(String, String), template::Mismatch> {
    Ok(if p.refine == 0 {
        (String::new(), String::new())
    } else {
        let fns = template::fill(
            template::REFINE,
            &[
                ("k", k.to_string()),
                ("shots", (2 * n).to_string()),
                ("refine", p.refine.to_string()),
                ("fd_gradient", lit(p.fd_gradient)),
                ("fd_curvature", lit(p.fd_curvature)),
            ],
        )?;
        let call = format!(
            "    let refined = atlas_{k}_refine(x, p, np, tv, rot, hmin);\n    tv = refined.t;\n    rot = refined.rot;\n    dist = length(tv);\n"
        );
        (fns, call)
    })
}

/// The atlas's field with its walks' pruning (`uv::prune`, mirrored by
/// `Pruning::field`): the body `body` (result `result`) evaluated with the walk's mask
/// inside the guard and the window, and again with every operand elsewhere; and the
/// mask of a walk, from the per-seed limits appended to `words` (the `tables` buffer).
fn pruned_field(
    k: usize,
    pr: &prune::Pruning,
    body: &str,
    result: &str,
    words: &mut Vec<u32>,
) -> String {
    let at = words.len();
    words.extend(pr.limit.iter().map(|&l| (l as f32).to_bits()));
    let candidates = pr.candidates.len();
    let (guard, window, eps) = (lit(prune::GUARD), lit(prune::WINDOW), lit(pr.eps));
    format!(
        "// The walk's pruning (uv/prune.rs): the mask of the union operands it evaluates, its
// seed and its reach; every bit set outside walks.
var<private> atlas_{k}_mask: u32 = 0xffffffffu;
var<private> atlas_{k}_centre: vec3<f32> = vec3<f32>(0.0, 0.0, 0.0);
var<private> atlas_{k}_reach: f32 = 0.0;
const ATLAS_{k}_PRUNE_AT: u32 = {at}u;

// A walk's mask: candidate c is skipped when the reach is below limit[j][c].
fn atlas_{k}_walk_mask(j: u32, reach: f32) -> u32 {{
    var mask = 0xffffffffu;
    for (var c = 0u; c < {candidates}u; c = c + 1u) {{
        if (reach < bitcast<f32>(tables[ATLAS_{k}_PRUNE_AT + j * {candidates}u + c])) {{
            mask = mask & ~(1u << c);
        }}
    }}
    return mask;
}}

// The field: pruned inside the walk's guard and window, whole elsewhere.
fn atlas_{k}_f(p: vec3<f32>) -> f32 {{
    sdf_evals = sdf_evals + 1u;
    if (atlas_{k}_mask != 0xffffffffu && length(p - atlas_{k}_centre) <= {guard} * atlas_{k}_reach + {eps}) {{
{body}        let v = {result}.x;
        if (abs(v) < {window} * atlas_{k}_reach + {eps}) {{
            return v;
        }}
        sdf_evals = sdf_evals + 1u;
    }}
    return atlas_{k}_whole(p);
}}
"
    )
}

/// The body of `atlas_K(x)`: Alg. 2, mirrored when the atlas has a `mirror` plane
/// (as `Atlas::sample_with`). Reflecting a rotation's quaternion (v, w) through the
/// plane of normal n gives (−reflect(v, n), w).
fn entry(k: usize, atlas: &Atlas) -> String {
    let Some(n) = atlas.mirror else {
        return format!("    return atlas_{k}_alg2(x);\n");
    };
    let n = vec3(n);
    format!(
        "    let n = {n};\n    let side = dot(x, n);\n    if (side >= 0.0) {{\n        return atlas_{k}_alg2(x);\n    }}\n    var s = atlas_{k}_alg2(x - 2.0 * side * n);\n    s.tangent = reflect(s.tangent, n);\n    s.bitangent = reflect(s.bitangent, n);\n    s.transport = vec4<f32>(-reflect(s.transport.xyz, n), s.transport.w);\n    return s;\n"
    )
}

/// `atlas_K_at(p, onto) -> AtlasSample`: what materials (`onto`) and the atlas views
/// read at a point of the render target (`Atlas::sample_at_with` on the CPU). Alg. 2 at
/// the rest point ω⁻¹(p) of the occurrence of the atlas's shape that p lies on (§5.1,
/// `ir::rest`), moved onto the surface with `onto`, with the frames carried back by the
/// inverse of ω⁻¹'s Jacobian.
pub fn at(k: usize, atlas: &Atlas) -> String {
    let rest = &atlas.rest;
    let mut out = String::new();
    if rest.is_identity() {
        out.push_str(&format!(
            "fn atlas_{k}_at(p: vec3<f32>, onto: bool) -> AtlasSample {{\n    if (onto) {{\n        return atlas_{k}(atlas_{k}_onto(p));\n    }}\n    return atlas_{k}(p);\n}}\n\n"
        ));
        return out;
    }
    // One function per occurrence: ω_i⁻¹.
    for (i, o) in rest.occurrences.iter().enumerate() {
        let mut body = String::new();
        let mut q = String::from("p");
        for (j, node) in o.steps.iter().enumerate() {
            let e = point_expr(node, &q).unwrap_or_else(|| q.clone());
            body.push_str(&format!("    let q{j} = {e};\n"));
            q = format!("q{j}");
        }
        out.push_str(&format!(
            "fn atlas_{k}_rest{i}(p: vec3<f32>) -> vec3<f32> {{\n{body}    return {q};\n}}\n\n"
        ));
    }
    // The occurrence whose rest point is nearest the surface.
    let mut pick = String::from("    var occ = 0u;\n    var q = atlas_0_rest0(p);\n")
        .replace("atlas_0_", &format!("atlas_{k}_"));
    if rest.occurrences.len() > 1 {
        pick.push_str(&format!("    var best = abs(atlas_{k}_f(q));\n"));
        for i in 1..rest.occurrences.len() {
            pick.push_str(&format!(
                "    let q{i} = atlas_{k}_rest{i}(p);\n    let f{i} = abs(atlas_{k}_f(q{i}));\n    if (f{i} < best) {{\n        best = f{i};\n        q = q{i};\n        occ = {i}u;\n    }}\n"
            ));
        }
    }
    let arms: String = rest
        .occurrences
        .iter()
        .enumerate()
        .map(|(i, _)| format!("        case {i}u: {{ return atlas_{k}_rest{i}(p); }}\n"))
        .collect();
    out.push_str(&format!(
        "fn atlas_{k}_rest(p: vec3<f32>, occ: u32) -> vec3<f32> {{\n    switch occ {{\n{arms}        default: {{ return p; }}\n    }}\n}}\n\n"
    ));
    let moves: Vec<String> = rest
        .occurrences
        .iter()
        .enumerate()
        .filter(|(_, o)| o.moves_frames())
        .map(|(i, _)| format!("occ == {i}u"))
        .collect();
    let frames = if moves.is_empty() {
        String::new()
    } else {
        format!(
            "    if ({}) {{\n        // The columns of ω⁻¹'s Jacobian; tangents map by its inverse (rows' cross products).\n        let h = {h};\n        let c0 = (atlas_{k}_rest(p + vec3<f32>(h, 0.0, 0.0), occ) - atlas_{k}_rest(p - vec3<f32>(h, 0.0, 0.0), occ)) / (2.0 * h);\n        let c1 = (atlas_{k}_rest(p + vec3<f32>(0.0, h, 0.0), occ) - atlas_{k}_rest(p - vec3<f32>(0.0, h, 0.0), occ)) / (2.0 * h);\n        let c2 = (atlas_{k}_rest(p + vec3<f32>(0.0, 0.0, h), occ) - atlas_{k}_rest(p - vec3<f32>(0.0, 0.0, h), occ)) / (2.0 * h);\n        let rows = transpose(mat3x3<f32>(c0, c1, c2));\n        let det = dot(rows[0], cross(rows[1], rows[2]));\n        if (abs(det) > 1e-12) {{\n            let inv = mat3x3<f32>(cross(rows[1], rows[2]), cross(rows[2], rows[0]), cross(rows[0], rows[1])) * (1.0 / det);\n            s.tangent = inv * s.tangent;\n            s.bitangent = inv * s.bitangent;\n        }}\n    }}\n",
            moves.join(" || "),
            h = lit(atlas.params.h_gradient)
        )
    };
    out.push_str(&format!(
        "fn atlas_{k}_at(p: vec3<f32>, onto: bool) -> AtlasSample {{\n{pick}    if (onto) {{\n        q = atlas_{k}_onto(q);\n    }}\n    var s = atlas_{k}(q);\n{frames}    return s;\n}}\n\n"
    ));
    out
}

/// The atlas's constants, read by the walk through small accessors (`atlas_K_p(j)`,
/// `_n`, `_e1`, `_offset`, `_adj_start`, `_adj`, `_adj_d`).
///
/// The seeds (position, normal, e1, offset) and the merge graph's adjacency (CSR, with
/// edge lengths) are baked in as `var<private>` arrays, as the design asks; with
/// `in_buffer` ([`SeedData`]: large atlases, or `--seed-data buffer`) they go to the
/// `tables` buffer instead, a record of [`SEED_WORDS`] floats per seed. Measured on lavapipe (docs/performance.md): baked,
/// the driver folds them and few-seed atlases render faster (sphere.sdf's loop walk
/// 18.5–19.0 against 22.6 ms), but naga parses every literal (about 13,000 instructions
/// each), so the buffer compiles faster (robot 10.5 → 9.5 ms, plate 11.8 → 9.1 ms). A
/// `const` array is worse than either: naga's SPIR-V copies it at each dynamic access.
/// On a GPU a private array lives in per-invocation local memory; a GPU should decide.
///
/// The seed grid's lists, whose size grows with seeds × cells, always go to `words`
/// (the `tables` buffer) with their offsets baked in: large baked arrays compile
/// super-linearly on some drivers (Mesa's lavapipe: the robot's 1,788-entry grid took
/// 111 s to its cs_atlas pipeline and 68 s to its render pipeline; 2.2 s and 2.8 s
/// without it).
///
/// A moving atlas (`moving`: room for that many adjacency entries; [`super::moving`])
/// has its records, and σ, in the buffer, where the host rewrites them.
fn tables(
    k: usize,
    atlas: &Atlas,
    grid: &SeedGrid,
    words: &mut Vec<u32>,
    in_buffer: bool,
    moving: Option<usize>,
) -> (String, Option<SeedsAt>) {
    let (mut text, at) = if in_buffer || moving.is_some() {
        let (text, at) = seeds_in_buffer(k, atlas, words, moving);
        (text, Some(at))
    } else {
        (seeds_baked(k, atlas), None)
    };
    let mut put = |name: &str, values: &mut dyn Iterator<Item = u32>| {
        text += &format!("const ATLAS_{k}_{name}_AT: u32 = {}u;\n", words.len());
        words.extend(values);
    };
    put("START", &mut grid.start.iter().copied());
    put("ITEMS", &mut grid.items.iter().copied());
    put(
        "BOUND",
        &mut grid.bound.iter().map(|&v| (v as f32).to_bits()),
    );
    (text, at)
}

/// The seeds and the adjacency as `var<private>` arrays, with their accessors.
fn seeds_baked(k: usize, atlas: &Atlas) -> String {
    let arr = |name: &str, ty: &str, items: Vec<String>| {
        // WGSL has no empty arrays: pad with one unused element.
        let items = if items.is_empty() {
            vec![match ty {
                "u32" => "0u".to_string(),
                "f32" => "0.0".to_string(),
                _ => format!("{ty}()"),
            }]
        } else {
            items
        };
        format!(
            "var<private> ATLAS_{k}_{name}: array<{ty}, {0}> = array<{ty}, {0}>({1});\n",
            items.len(),
            items.join(", ")
        )
    };
    let seeds = &atlas.seeds;
    let (start, adj, adj_d) = adjacency(atlas);
    let mut text = String::new();
    text += &arr("P", "vec3f", seeds.iter().map(|s| vec3(s.seed.p)).collect());
    text += &arr("N", "vec3f", seeds.iter().map(|s| vec3(s.seed.n)).collect());
    text += &arr(
        "E1",
        "vec3f",
        seeds.iter().map(|s| vec3(s.seed.e1)).collect(),
    );
    text += &arr(
        "OFFSET",
        "vec2f",
        seeds
            .iter()
            .map(|s| format!("vec2f({}, {})", arg(s.offset.x), arg(s.offset.y)))
            .collect(),
    );
    let u = |v: Vec<u32>| v.into_iter().map(|x| format!("{x}u")).collect();
    text += &arr("ADJ_START", "u32", u(start));
    text += &arr("ADJ", "u32", u(adj));
    text += &arr("ADJ_D", "f32", adj_d.into_iter().map(arg).collect());
    text += &accessors(
        k,
        [
            format!("ATLAS_{k}_P[j]"),
            format!("ATLAS_{k}_N[j]"),
            format!("ATLAS_{k}_E1[j]"),
            format!("ATLAS_{k}_OFFSET[j]"),
            format!("ATLAS_{k}_ADJ_START[i]"),
            format!("ATLAS_{k}_ADJ[t]"),
            format!("ATLAS_{k}_ADJ_D[t]"),
        ],
    );
    text
}

/// The seeds' records and the adjacency appended to `words` (the `tables` buffer), with
/// their offsets and accessors; a moving atlas's with room for `moving` adjacency
/// entries and its σ.
fn seeds_in_buffer(
    k: usize,
    atlas: &Atlas,
    words: &mut Vec<u32>,
    moving: Option<usize>,
) -> (String, SeedsAt) {
    let at = reserve(atlas, moving.unwrap_or(0), moving.is_some(), words);
    let mut text = String::new();
    let mut put = |name: &str, offset: u32| {
        text += &format!("const ATLAS_{k}_{name}_AT: u32 = {offset}u;\n");
    };
    put("SEEDS", at.seeds);
    put("ADJ_START", at.adj_start);
    put("ADJ", at.adj);
    put("ADJ_D", at.adj_d);
    if let Some(s) = at.sigma {
        put("SIGMA", s);
    }
    let w = SEED_WORDS;
    let word = |at: String| format!("bitcast<f32>(tables[{at}])");
    let vec3 = |at: &str| {
        format!(
            "vec3<f32>({}, {}, {})",
            word(at.to_string()),
            word(format!("{at} + 1u")),
            word(format!("{at} + 2u"))
        )
    };
    let seed = |field: usize| format!("ATLAS_{k}_SEEDS_AT + {w}u * j + {field}u");
    text += &accessors(
        k,
        [
            vec3(&seed(0)),
            vec3(&seed(3)),
            vec3(&seed(6)),
            format!("vec2<f32>({}, {})", word(seed(9)), word(seed(10))),
            format!("tables[ATLAS_{k}_ADJ_START_AT + i]"),
            format!("tables[ATLAS_{k}_ADJ_AT + t]"),
            word(format!("ATLAS_{k}_ADJ_D_AT + t")),
        ],
    );
    (text, at)
}

/// The accessors of an atlas's seeds and adjacency, given their bodies' expressions
/// (of `j` for the seeds, `i` for the starts, `t` for the entries).
fn accessors(k: usize, [p, n, e1, offset, start, adj, adj_d]: [String; 7]) -> String {
    format!(
        "// Seed j's position, normal, e1 and uv offset.
fn atlas_{k}_p(j: u32) -> vec3<f32> {{
    return {p};
}}

fn atlas_{k}_n(j: u32) -> vec3<f32> {{
    return {n};
}}

fn atlas_{k}_e1(j: u32) -> vec3<f32> {{
    return {e1};
}}

fn atlas_{k}_offset(j: u32) -> vec2<f32> {{
    return {offset};
}}

// Seed i's merged neighbours are entries adj_start(i) .. adj_start(i + 1) of the adjacency.
fn atlas_{k}_adj_start(i: u32) -> u32 {{
    return {start};
}}

fn atlas_{k}_adj(t: u32) -> u32 {{
    return {adj};
}}

fn atlas_{k}_adj_d(t: u32) -> f32 {{
    return {adj_d};
}}

"
    )
}

//! Random scenes of the §5 features (`section5_scene`): displacement, shell maps,
//! atlases with `mirror`, `refine`, several seeds and merges, normal maps, textured CSG,
//! atlases on displaced (or shell-mapped) shapes and chains of them, rest-pose warps
//! (twist, mirror) and unbounded shapes with extreme scales. The generic generator
//! (`scene`) reaches `displace` and `shell_map` only with constant heights and uv, as
//! warps do not take surface fields in the builtins table; this one knows §5's rules:
//!
//! - a height or a shell map's uv reads at most one atlas, which is on the displaced
//!   shape itself (E0206), through smooth math with a bounded range (E0207);
//! - an atlas on a displaced shape walks the height's atlas at every evaluation, so the
//!   atlases of a chain nest; more than 2 deep is E0119, and walks nested in the
//!   unrolled form are usually too large for a driver (E0118);
//! - a normal map's uv comes from exactly one atlas (E0209).
//!
//! Besides those: displacements and shell maps in either order in one method chain,
//! shapes painted before they are displaced, tiles displaced by their own atlas (walks
//! in shell coordinates), atlases on a union of a shape with another far away, and a
//! render of painted operands under hard and smooth CSG, moved and warped (twist,
//! mirror, bend, repeat, elongate: rest-pose queries).
//!
//! Seeds are placed on the base shapes' surfaces (a displaced surface lies within the
//! displacement of its base's, so seeds there are projected, N0001). A few scenes break
//! one of the rules on purpose (an atlas on another shape, a jump), a few use extreme
//! scales, bands, thicknesses and uv (1e30, 1.8e38, 1e-30, on unbounded shapes too:
//! E0403 is then right, and the scene is `far`), and a tenth get one mutation of the
//! generic generator.

use super::{mutate, Rng, Scene};

/// The texture every scene reads (tests/ui/textures, as the generic generator's).
const IMAGE: &str = "\"textures/bricks.png\"";

/// Where seeds can be placed: the surface of a base shape, centred at the origin.
#[derive(Debug, Clone, Copy)]
enum Surf {
    /// A sphere (also a lattice of spheres: its central one).
    Sphere { r: f64 },
    /// A sphere with a smaller one blended on top: seeds on its lower half.
    Blob { r: f64 },
    /// The plane y = `y`, normal +y.
    Plane { y: f64 },
    /// A cylinder along y: seeds on its side, near the middle.
    Cylinder { r: f64, h: f64 },
    /// A box of full sizes `s`: seeds on its +z face.
    Box { s: [f64; 3] },
    /// A torus in the xz-plane: seeds on its outer equator.
    Torus { major: f64, minor: f64 },
}

/// A named shape.
#[derive(Debug, Clone)]
struct Shape {
    name: String,
    /// Where its (or its base's) surface is.
    surf: Surf,
    /// How deep the walks of an atlas on it would nest: 0 on a plain shape, else one
    /// more than the deepest atlas its heights read.
    nest: u32,
    /// The atlases declared on it.
    atlases: Vec<usize>,
    /// The atlas of the shape it was displaced from (its materials may read it).
    base_atlas: Option<usize>,
    /// Whether it was displaced or shell-mapped.
    derived: bool,
    /// Whether it or a shape it comes from was shell-mapped (its surface is tiles: few
    /// merges reach).
    rough: bool,
}

#[derive(Debug, Clone)]
struct Atlas {
    name: String,
    /// The index of its shape.
    shape: usize,
    /// Its walks' nesting (1: walks of a plain shape).
    nest: u32,
    /// Its largest `max_distance`, for the fades of heights.
    reach: f64,
}

struct Gen5 {
    rng: Rng,
    items: Vec<String>,
    counter: usize,
    textures: Vec<String>,
    shapes: Vec<Shape>,
    atlases: Vec<Atlas>,
    materials: Vec<String>,
    far: bool,
}

/// Generates the §5 scene of `seed`.
pub fn section5_scene(seed: u64) -> Scene {
    let mut g = Gen5 {
        // Another stream than `scene(seed)`'s.
        rng: Rng::new(seed ^ 0x5EC7_1055_0005_0005),
        items: Vec::new(),
        counter: 0,
        textures: Vec::new(),
        shapes: Vec::new(),
        atlases: Vec::new(),
        materials: Vec::new(),
        far: false,
    };
    g.file();
    let mut text = g.items.join("\n");
    text.push('\n');
    let mut mutation = None;
    if g.rng.chance(0.1) {
        let (name, t) = mutate(&mut g.rng, &text);
        mutation = Some(name);
        text = t;
    }
    Scene {
        seed,
        text,
        mutation,
        far: g.far,
    }
}

/// `x` with at most 4 decimals, without trailing zeros.
fn num(x: f64) -> String {
    let s = format!("{x:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    match s {
        "-0" | "" => "0".to_string(),
        s => s.to_string(),
    }
}

fn vec3(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", num(v[0]), num(v[1]), num(v[2]))
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalized(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt().max(1e-12);
    [a[0] / l, a[1] / l, a[2] / l]
}

/// `p` reflected onto the positive side of the plane through the origin with normal `m`.
fn positive_side(p: [f64; 3], m: [f64; 3]) -> [f64; 3] {
    let d = dot(p, m) / dot(m, m);
    if d >= 0.0 {
        p
    } else {
        [
            p[0] - 2.0 * d * m[0],
            p[1] - 2.0 * d * m[1],
            p[2] - 2.0 * d * m[2],
        ]
    }
}

impl Surf {
    /// A point of the surface for the parameters (a, b) in [0, 1)², and the normal
    /// there; the seeds of one atlas have nearby parameters ([`Surf::patch`]).
    fn point(self, a: f64, b: f64) -> ([f64; 3], [f64; 3]) {
        use std::f64::consts::{PI, TAU};
        match self {
            Surf::Sphere { r } | Surf::Blob { r } => {
                let th = a * TAU;
                let ph = match self {
                    // Below the blended top sphere.
                    Surf::Blob { .. } => PI * (0.6 + 0.35 * b),
                    _ => PI * (0.15 + 0.7 * b),
                };
                let n = [ph.sin() * th.cos(), ph.cos(), ph.sin() * th.sin()];
                ([r * n[0], r * n[1], r * n[2]], n)
            }
            Surf::Plane { y } => ([(a - 0.5) * 2.0, y, (b - 0.5) * 2.0], [0.0, 1.0, 0.0]),
            Surf::Cylinder { r, h } => {
                let th = a * TAU;
                let n = [th.cos(), 0.0, th.sin()];
                ([r * n[0], (b - 0.5) * h * 0.5, r * n[2]], n)
            }
            Surf::Box { s } => (
                [(a - 0.5) * s[0] * 0.5, (b - 0.5) * s[1] * 0.5, s[2] * 0.5],
                [0.0, 0.0, 1.0],
            ),
            Surf::Torus { major, minor } => {
                let th = a * TAU;
                // Around the outer equator, within ±0.6 rad of the tube.
                let ph = (b - 0.5) * 1.2;
                let ring = [th.cos(), 0.0, th.sin()];
                let n = [ring[0] * ph.cos(), ph.sin(), ring[2] * ph.cos()];
                (
                    [
                        major * ring[0] + minor * n[0],
                        minor * n[1],
                        major * ring[2] + minor * n[2],
                    ],
                    n,
                )
            }
        }
    }

    /// The size of a patch of nearby seeds, in parameter units.
    fn patch(self) -> f64 {
        match self {
            Surf::Sphere { .. } | Surf::Blob { .. } => 0.06,
            Surf::Cylinder { .. } | Surf::Torus { .. } => 0.05,
            Surf::Plane { .. } | Surf::Box { .. } => 0.25,
        }
    }
}

impl Gen5 {
    fn fresh(&mut self, prefix: &str) -> String {
        self.counter += 1;
        format!("{prefix}{}", self.counter)
    }

    fn pick_str(&mut self, xs: &[&str]) -> String {
        self.rng.pick(xs).to_string()
    }

    fn texture(&mut self) -> String {
        if self.textures.is_empty() || self.rng.chance(0.15) {
            let name = self.fresh("tex");
            let e = if self.rng.chance(0.5) {
                format!("image({IMAGE})")
            } else {
                format!("image(path: {IMAGE})")
            };
            self.items.push(format!("let {name} = {e};"));
            self.textures.push(name);
        }
        self.rng.pick(&self.textures).clone()
    }

    // ---------------------------------------------------------------- the file

    fn file(&mut self) {
        if self.rng.chance(0.5) {
            self.texture();
        }
        let bases = 1 + self.rng.below(3);
        for _ in 0..bases {
            let s = self.base();
            if self.rng.chance(0.85) {
                let own = self.rng.chance(0.92);
                self.atlas_on(s, own);
            }
        }
        // Chains: an atlas on a shape displaced (or shell-mapped) by a field of the
        // previous shape's atlas, 1 to 3 deep (3 is over the nesting limit: E0119).
        let bases: Vec<usize> = (0..self.shapes.len()).collect();
        let mut tops = bases.clone();
        let chains = self.rng.below(3);
        for _ in 0..chains {
            let depth = *self.rng.pick(&[1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 3]);
            // Mostly from a base: a chain from a chain's end nests deeper.
            let from = if self.rng.chance(0.8) {
                *self.rng.pick(&bases)
            } else {
                *self.rng.pick(&tops)
            };
            let top = self.chain(from, depth);
            tops.push(top);
        }
        // One-off displacements and shell maps of any shape, in method chains, with
        // constant, positional or atlas fields.
        for _ in 0..self.rng.below(3) {
            let from = *self.rng.pick(&tops);
            let ops = 1 + self.rng.below(2);
            let s = self.derived(from, ops, None);
            tops.push(s);
        }
        // Unbounded shapes, sometimes at extreme scales.
        if self.rng.chance(0.2) {
            let s = self.unbounded_extreme();
            tops.push(s);
        }
        self.render(&tops);
    }

    /// A base shape, centred at the origin, bound by `let`.
    fn base(&mut self) -> usize {
        let (e, surf) = match self.rng.below(9) {
            0..=2 => {
                let r = *self.rng.pick(&[0.5, 0.8, 1.0, 1.5]);
                let e = if self.rng.chance(0.5) {
                    format!("sphere({})", num(r))
                } else {
                    format!("sphere(radius: {})", num(r))
                };
                (e, Surf::Sphere { r })
            }
            3 => {
                let r = *self.rng.pick(&[0.8, 1.0]);
                (
                    format!(
                        "smooth_union(sphere({}), sphere({}).translate([0, {}, 0]), {})",
                        num(r),
                        num(r * 0.6),
                        num(r * 1.1),
                        self.pick_str(&["0.15", "0.2", "0.3"])
                    ),
                    Surf::Blob { r },
                )
            }
            4 => {
                let r = *self.rng.pick(&[0.4, 0.5, 0.6]);
                let h = *self.rng.pick(&[2.0, 2.4]);
                let round = if self.rng.chance(0.4) {
                    ".round(0.04)"
                } else {
                    ""
                };
                (
                    format!("cylinder(radius: {}, height: {}){round}", num(r), num(h)),
                    Surf::Cylinder { r, h },
                )
            }
            5 => {
                let s = [
                    *self.rng.pick(&[1.0, 1.6]),
                    *self.rng.pick(&[0.8, 1.2]),
                    *self.rng.pick(&[0.6, 1.0]),
                ];
                let e = if self.rng.chance(0.5) {
                    format!("box({})", vec3(s))
                } else {
                    format!("round_box({}, radius: 0.05)", vec3(s))
                };
                (e, Surf::Box { s })
            }
            6 => {
                let (major, minor) = *self.rng.pick(&[(1.0, 0.3), (0.8, 0.25)]);
                (
                    format!("torus(major: {}, minor: {})", num(major), num(minor)),
                    Surf::Torus { major, minor },
                )
            }
            7 => {
                let y = *self.rng.pick(&[0.0, -1.0, 0.5]);
                let e = if y == 0.0 && self.rng.chance(0.5) {
                    "plane()".to_string()
                } else {
                    format!("plane(normal: [0, 1, 0], offset: {})", num(y))
                };
                (e, Surf::Plane { y })
            }
            _ => {
                let r = *self.rng.pick(&[0.4, 0.5]);
                (
                    format!(
                        "sphere({}).repeat({})",
                        num(r),
                        self.pick_str(&["2", "1.5", "[2, 3, 2]"])
                    ),
                    Surf::Sphere { r },
                )
            }
        };
        self.bind(e, surf, 0, None, false)
    }

    fn bind(
        &mut self,
        e: String,
        surf: Surf,
        nest: u32,
        base_atlas: Option<usize>,
        derived: bool,
    ) -> usize {
        let e_rough = e.contains(".shell_map(");
        let name = self.fresh(if derived { "d" } else { "b" });
        self.items.push(format!("let {name} = {e};"));
        self.shapes.push(Shape {
            name,
            surf,
            nest,
            atlases: Vec::new(),
            base_atlas,
            derived,
            rough: e_rough,
        });
        self.shapes.len() - 1
    }

    /// An atlas on shape `s`: 1 to 4 seeds in one patch, merges, `mirror`, `refine`.
    fn atlas(&mut self, s: usize) -> usize {
        self.atlas_on(s, true)
    }

    /// An atlas on shape `s` (`own`), or on its union with a shape far away (as in
    /// tests/ui/atlas_on_displaced.sdf; then not an atlas of `s` itself).
    fn atlas_on(&mut self, s: usize, own: bool) -> usize {
        let name = self.fresh("atlas");
        let surf = self.shapes[s].surf;
        let mut body = Vec::new();
        let steps = 6 + self.rng.below(15);
        if self.rng.chance(0.8) {
            body.push(format!("    steps = {steps};"));
        }
        let mut reach = 3.0;
        if self.rng.chance(0.4) {
            reach = *self.rng.pick(&[1.5, 2.0, 2.5, 4.0]);
            body.push(format!("    max_distance = {};", num(reach)));
        }
        if self.rng.chance(0.6) {
            let k = self.pick_str(&["0", "1", "2", "2", "1.0"]);
            body.push(format!("    refine = {k};"));
        }
        let mirror = if self.rng.chance(0.35) {
            let m = *self.rng.pick(&[
                [1.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [-1.0, 0.0, 0.0],
            ]);
            body.push(format!("    mirror = {};", vec3(m)));
            Some(m)
        } else {
            None
        };
        if self.rng.chance(0.15) {
            body.push(format!(
                "    sigma = {};",
                self.pick_str(&["0.1", "0.05", "0.3"])
            ));
        }
        if self.rng.chance(0.1) {
            body.push("    reproject = true;".to_string());
        }
        let n = 1 + self.rng.below(4);
        let (ca, cb) = (self.rng.unit(), self.rng.unit());
        let w = surf.patch();
        let mut seeds = Vec::new();
        for i in 0..n {
            let a = ca + (self.rng.unit() - 0.5) * w;
            let b = (cb + (self.rng.unit() - 0.5) * w).clamp(0.0, 1.0);
            let (mut p, mut nrm) = surf.point(a, b);
            if let Some(m) = mirror {
                if dot(p, m) < 0.0 {
                    p = positive_side(p, m);
                    nrm = positive_side(nrm, m);
                    // A reflection of the normal about the plane.
                    if dot(nrm, m) < 0.0 {
                        nrm = positive_side(nrm, m);
                    }
                }
            }
            let seed = format!("p{i}");
            let tangent = if self.rng.chance(0.5) {
                let up = if nrm[1].abs() > 0.9 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                format!(" tangent {}", vec3(normalized(cross(up, nrm))))
            } else {
                String::new()
            };
            body.push(format!("    seed {seed} = {}{tangent};", vec3(p)));
            seeds.push(seed);
        }
        let merges = if self.shapes[s].rough { 0.1 } else { 0.65 };
        if n >= 2 && self.rng.chance(merges) {
            let k = 2 + self.rng.below(n - 1);
            let mut chain: Vec<String> = seeds[..k].to_vec();
            if self.rng.chance(0.5) {
                chain.reverse();
            }
            body.push(format!("    merge {};", chain.join(" ")));
            if k < n && self.rng.chance(0.3) {
                body.push(format!("    merge {} {};", seeds[k - 1], seeds[k]));
            }
        }
        if self.rng.chance(0.3) {
            // Settings after seeds: the order inside a block is free.
            body.rotate_left(1);
        }
        let target = if own {
            self.shapes[s].name.clone()
        } else {
            let far = self.pick_str(&[
                "box(0.5).translate([4, 0, 0])",
                "sphere(0.3).translate([0, 5, 0])",
            ]);
            format!("{} | {far}", self.shapes[s].name)
        };
        self.items.push(format!(
            "atlas {name} on {target} {{\n{}\n}}",
            body.join("\n")
        ));
        let nest = self.shapes[s].nest + 1;
        self.atlases.push(Atlas {
            name,
            shape: s,
            nest,
            reach,
        });
        let k = self.atlases.len() - 1;
        if own {
            self.shapes[s].atlases.push(k);
        }
        k
    }

    /// An atlas of shape `s`, declared if it has none.
    fn atlas_of(&mut self, s: usize) -> usize {
        match self.shapes[s].atlases.first() {
            Some(&a) if self.rng.chance(0.85) => a,
            _ => self.atlas(s),
        }
    }

    /// `depth` levels, each displacing (or shell-mapping) the previous shape by a field of
    /// the atlas on it; returns the last shape.
    fn chain(&mut self, from: usize, depth: usize) -> usize {
        let mut cur = from;
        for _ in 0..depth {
            let a = self.atlas_of(cur);
            let ops = 1 + usize::from(self.rng.chance(0.25));
            cur = self.derived(cur, ops, Some(a));
        }
        // Sometimes an atlas on the chain's end too, which materials may read (one more
        // level of nesting).
        if self.rng.chance(if depth < 2 { 0.3 } else { 0.1 }) {
            self.atlas(cur);
        }
        cur
    }

    /// Shape `from` displaced or shell-mapped `ops` times in one method chain; the first
    /// call's field may read `atlas` (on `from`), the later ones constants or positions
    /// (their shapes have no atlas: an atlas there would be E0206).
    fn derived(&mut self, from: usize, ops: usize, atlas: Option<usize>) -> usize {
        let mut e = self.shapes[from].name.clone();
        let mut nest = self.shapes[from].nest;
        let atlas = atlas.or_else(|| {
            let own = self.shapes[from].atlases.clone();
            if !own.is_empty() && self.rng.chance(0.7) {
                Some(own[self.rng.below(own.len())])
            } else {
                None
            }
        });
        // Painted before it is displaced: heights may still read the atlas (`paint` aside).
        if self.rng.chance(0.1) {
            let m = self.material(from);
            e = format!("{e}.paint({m})");
        }
        for i in 0..ops {
            let mut reads = if i == 0 { atlas } else { None };
            // On purpose, rarely: a field of an atlas on another shape (E0206).
            if self.rng.chance(0.01) && !self.atlases.is_empty() {
                reads = Some(self.rng.below(self.atlases.len()));
            }
            if let Some(a) = reads {
                nest = nest.max(self.atlases[a].nest);
            }
            // Rarely an extreme scale, band or thickness (then E0403 is a right answer).
            let extreme = self.rng.chance(0.015);
            if extreme {
                self.far = true;
            }
            if self.rng.chance(0.6) {
                let h = self.height(reads);
                let scale = if extreme {
                    self.pick_str(&["1e30", "1.8e38", "1e-30", "3.4e38", "1e20"])
                } else {
                    self.pick_str(&["0.02", "0.05", "0.1", "0.08", "0.03"])
                };
                let mut args = vec![h];
                // Without `scale` (1), rarely: seeds are placed for small ones.
                match self.rng.below(10) {
                    0 => {}
                    1..=4 => args.push(format!("scale: {scale}")),
                    5..=6 => args.push(scale),
                    _ => {
                        args.push(format!("scale: {scale}"));
                        let band = if extreme {
                            self.pick_str(&["1e30", "1.0000001", "3.4e38"])
                        } else {
                            self.pick_str(&["1.5", "2", "4"])
                        };
                        args.push(format!("band: {band}"));
                    }
                }
                if self.rng.chance(0.15) {
                    e = format!("displace({e}, {})", args.join(", "));
                } else {
                    e = format!("{e}.displace({})", args.join(", "));
                }
            } else {
                let (tile, tile_nest) = self.tile();
                nest = nest.max(tile_nest);
                let mut uv = self.shell_uv(reads);
                if extreme && self.rng.chance(0.5) {
                    uv = format!("({uv}) * {}", self.pick_str(&["1e30", "1e-30", "1e20"]));
                }
                let mut args = vec![tile, uv];
                if extreme || self.rng.chance(0.7) {
                    let t = if extreme {
                        self.pick_str(&["1e30", "1e-30", "1.8e38", "1e-20"])
                    } else {
                        self.pick_str(&["0.1", "0.15", "0.2", "0.25"])
                    };
                    args.push(format!("thickness: {t}"));
                }
                if self.rng.chance(0.4) {
                    args.push(format!("base: {}", self.pick_str(&["true", "false"])));
                }
                e = format!("{e}.shell_map({})", args.join(", "));
            }
        }
        let surf = self.shapes[from].surf;
        let base_atlas = atlas.or(self.shapes[from].base_atlas);
        let s = self.bind(e, surf, nest, base_atlas, true);
        self.shapes[s].rough |= self.shapes[from].rough;
        s
    }

    /// A texture channel at `a`'s uv (scaled, offset, wrapped).
    fn channel(&mut self, a: &str) -> String {
        let t = self.texture();
        let uv = match self.rng.below(4) {
            0 => format!("{a}.uv"),
            1 => format!("{a}.uv * {}", self.pick_str(&["0.5", "2", "1.5", "3"])),
            2 => format!("{a}.uv * [1, 0.8] + [0.25, 0.5]"),
            _ => format!("({a}.uv - [1, 1]) / [2, 2]"),
        };
        let wrap = self.pick_str(&[
            "",
            "",
            ", wrap: \"clamp\"",
            ", \"mirror\"",
            ", wrap: \"repeat\"",
        ]);
        let c = self.pick_str(&["r", "g", "b", "a", "x"]);
        if self.rng.chance(0.5) {
            format!("{t}.sample({uv}{wrap}).{c}")
        } else {
            format!("sample({t}, {uv}{wrap}).{c}")
        }
    }

    /// A fade to 0 before atlas `a`'s reach ends.
    fn fade(&mut self, a: usize) -> String {
        let r = self.atlases[a].reach;
        format!(
            "smoothstep({}, {}, {}.distance)",
            num(r * 0.9),
            num(r * 0.7),
            self.atlases[a].name
        )
    }

    /// A displacement height: a constant, smooth math of positions, or a field of atlas
    /// `a` (texture channels, math of its uv and distance); rarely a jump (E0207).
    fn height(&mut self, a: Option<usize>) -> String {
        let constant = |g: &mut Gen5| g.pick_str(&["0.5", "1", "-0.25", "0", "0.75", "-1"]);
        let Some(k) = a else {
            return match self.rng.below(4) {
                0 | 1 => constant(self),
                2 => format!(
                    "0.5 + 0.5 * sin(position.{} * {})",
                    self.pick_str(&["x", "y", "z"]),
                    self.pick_str(&["3", "8", "20"])
                ),
                _ => format!("smoothstep(-1, 1, position.y) * {}", constant(self)),
            };
        };
        let name = self.atlases[k].name.clone();
        let kk = |g: &mut Gen5| g.pick_str(&["2", "4", "8", "12", "0.5"]);
        // On purpose, rarely: a jump, or a range without a bound (E0207).
        let pick = if self.rng.chance(0.015) {
            13
        } else {
            self.rng.below(13)
        };
        match pick {
            0 => constant(self),
            1 | 2 => self.channel(&name),
            3 => {
                let c = self.channel(&name);
                format!("{c} * {}", self.fade(k))
            }
            4 => {
                let c = self.channel(&name);
                let f = self.fade(k);
                format!("mix({}, {c}, {f})", constant(self))
            }
            5 | 6 => format!("sin({name}.uv.x * {})", kk(self)),
            7 => format!(
                "0.5 + 0.5 * sin({name}.uv.x * {}) * cos({name}.uv.y * {})",
                kk(self),
                kk(self)
            ),
            8 => match self.rng.below(3) {
                0 => format!(
                    "clamp({name}.distance, 0, 2) * {}",
                    self.pick_str(&["0.1", "1"])
                ),
                1 => format!("sin({name}.distance * 3)"),
                _ => format!("min({name}.distance, {}) - 1", num(self.atlases[k].reach)),
            },
            9 => format!("smoothstep(0, 2, {name}.distance)"),
            10 => format!("clamp({name}.uv.x, -1, 1) * clamp({name}.uv.y, -1, 1)"),
            11 => format!("sin(length({name}.uv) * {})", kk(self)),
            12 => format!(
                "cos({name}.uv.y * {}) * {} + sin(position.x * 2) * 0.25",
                kk(self),
                self.fade(k)
            ),
            _ => match self.rng.below(4) {
                0 => format!("floor({name}.uv.x * 4) / 4"),
                1 => format!("{name}.uv.x * 0.1"),
                2 => format!("{name}.distance * 0.1"),
                _ => format!("step(0.5, sin({name}.uv.y))"),
            },
        }
    }

    /// A shell map's uv: a constant, positions, or atlas `a`'s uv.
    fn shell_uv(&mut self, a: Option<usize>) -> String {
        let Some(k) = a else {
            return match self.rng.below(3) {
                0 => self.pick_str(&["[0.5, 0.5]", "[0.25, -0.5]", "[0, 0]"]),
                1 => format!(
                    "position.{} * {}",
                    self.pick_str(&["xz", "xy", "zy"]),
                    self.pick_str(&["2", "3", "0.5"])
                ),
                _ => "[sin(position.x * 2), cos(position.z * 2)]".to_string(),
            };
        };
        let name = self.atlases[k].name.clone();
        match self.rng.below(7) {
            0 => format!("{name}.uv"),
            1 | 2 => format!("{name}.uv * {}", self.pick_str(&["2", "3", "4"])),
            3 => format!("{name}.uv * [3, 2]"),
            4 => format!("[{name}.uv.x * 3, {name}.uv.y * 2]"),
            5 => format!("({name}.uv + [0.5, 0.5]) * 2"),
            _ => format!("[sin({name}.uv.x) * 2, {name}.uv.y * 3]"),
        }
    }

    /// A tile: a small shape standing in the cell x, z in [-0.5, 0.5], y in [-1, 1], and
    /// how deep the walks of its atlas nest (0: none). Sometimes a tile displaced by a
    /// field of its own atlas, so that walks run in shell coordinates.
    fn tile(&mut self) -> (String, u32) {
        if self.rng.chance(0.1) {
            let r = *self.rng.pick(&[0.25, 0.3]);
            let t = self.bind(
                format!("sphere({})", num(r)),
                Surf::Sphere { r },
                0,
                None,
                false,
            );
            let a = self.atlas(t);
            let d = self.derived(t, 1, Some(a));
            return (self.shapes[d].name.clone(), self.shapes[d].nest);
        }
        let t = self.pick_str(&[
            "sphere(0.3)",
            "sphere(0.2).translate([0, 0.5, 0])",
            "cylinder(radius: 0.12, height: 1.2).translate([0, 0.1, 0]) | sphere(0.3).translate([0, 0.65, 0])",
            "box([0.4, 1.2, 0.4])",
            "capsule(a: [-0.3, 0.3, 0], b: [0.1, 0.3, 0], radius: 0.07)",
            "torus(0.25, 0.08)",
            "round_box([0.5, 0.8, 0.5], radius: 0.05)",
            "sphere(0.3).displace(0.5, scale: 0.1)",
            "box([0.3, 1.5, 0.3]).twist(rate: 2)",
            "smooth_union(sphere(0.2), box([0.2, 1, 0.2]), 0.1)",
        ]);
        (t, 0)
    }

    /// A plane or a lattice displaced or shell-mapped, sometimes at extreme scales
    /// (beyond 1e10 the scene is `far`: E0403 is a right answer).
    fn unbounded_extreme(&mut self) -> usize {
        let base = if self.rng.chance(0.5) {
            "plane()".to_string()
        } else {
            format!("sphere(0.5).repeat({})", self.pick_str(&["2", "[2, 3, 2]"]))
        };
        let huge = self.rng.chance(0.7);
        let s = if huge {
            self.pick_str(&["1e30", "1.8e38", "1e31", "3.4e38", "1e20", "1e-30"])
        } else {
            self.pick_str(&["0.1", "1", "10"])
        };
        let x: f64 = s.parse().unwrap();
        self.far |= !(1e-10..=1e10).contains(&x);
        let e = match self.rng.below(4) {
            0 => format!("{base}.displace(1, scale: {s})"),
            1 => format!(
                "{base}.displace(0.5 + 0.5 * sin(position.x * 4), scale: {s}, band: 3)"
            ),
            2 => format!("{base}.shell_map(sphere(0.3), position.xz, thickness: {s})"),
            _ => format!(
                "{base}.displace(0.5, scale: {s}).shell_map(sphere(0.3), [0.5, 0.5], thickness: {})",
                self.pick_str(&["0.2", "1e30"])
            ),
        };
        if e.contains("1e30)") {
            self.far = true;
        }
        self.bind(e, Surf::Plane { y: 0.0 }, 0, None, true)
    }

    // ---------------------------------------------------------------- materials

    /// A material for shape `s`, reading one of its atlases (or its base's).
    fn material(&mut self, s: usize) -> String {
        let mut choices: Vec<usize> = self.shapes[s].atlases.clone();
        if let Some(b) = self.shapes[s].base_atlas {
            // The base's atlas: cheaper, and preferred.
            choices.extend([b, b, b]);
        }
        if choices.is_empty() || self.rng.chance(0.1) {
            // Any atlas (a material may read any), or none.
            if !self.atlases.is_empty() && self.rng.chance(0.7) {
                choices.push(self.rng.below(self.atlases.len()));
            }
        }
        let a = if choices.is_empty() {
            None
        } else {
            Some(self.atlases[*self.rng.pick(&choices)].name.clone())
        };
        let name = self.fresh("m");
        let mut body = Vec::new();
        let k = self.pick_str(&["1", "1.5", "2", "0.5"]);
        match &a {
            Some(a) => {
                let t = self.texture();
                body.push(match self.rng.below(4) {
                    0 => format!("    color = {t}.sample({a}.uv * {k}).rgb;"),
                    1 => format!(
                        "    color = mix([0.15, 0.3, 0.55], [0.85, 0.85, 0.8], checker({a}.uv, 4));"
                    ),
                    2 => format!("    color = [{a}.uv * 0.25 + [0.5, 0.5], 0.5];"),
                    _ => format!("    color = sample({t}, {a}.uv, wrap: \"mirror\");"),
                });
                if self.rng.chance(0.5) {
                    body.push(format!("    roughness = {}.sample({a}.uv * {k}).r;", t));
                }
                if self.rng.chance(0.6) {
                    let t = self.texture();
                    let strength =
                        self.pick_str(&["", ", strength: 1.2", ", strength: 0", ", 0.5"]);
                    let conv = self.pick_str(&["", ", convention: \"dx\"", ", convention: \"gl\""]);
                    let wrap = self.pick_str(&["", ", wrap: \"clamp\""]);
                    // A positional strength (", 0.5") comes before the named ones.
                    let extra = format!("{strength}{conv}{wrap}");
                    body.push(if self.rng.chance(0.5) {
                        format!("    normal = {t}.sample_normal({a}.uv * {k}{extra});")
                    } else {
                        format!("    normal = sample_normal({t}, {a}.uv{extra});")
                    });
                }
            }
            None => {
                body.push(format!(
                    "    color = [0.5 + 0.5 * sin(position.x * 4), 0.6, {}];",
                    self.pick_str(&["0.3", "0.8"])
                ));
            }
        }
        if self.rng.chance(0.3) {
            body.push(format!(
                "    metallic = {};",
                self.pick_str(&["0.2", "1", "0"])
            ));
        }
        if self.rng.chance(0.3) {
            body.reverse();
        }
        self.items
            .push(format!("material {name} {{\n{}\n}}", body.join("\n")));
        self.materials.push(name.clone());
        name
    }

    // ---------------------------------------------------------------- the render

    /// An operand of the render: a shape, painted, moved or warped (rest pose).
    fn operand(&mut self, s: usize) -> String {
        let mut e = self.shapes[s].name.clone();
        if self.rng.chance(0.75) {
            let m = self.material(s);
            e = if self.rng.chance(0.8) {
                format!("{e}.paint({m})")
            } else {
                format!("paint({e}, {m})")
            };
        }
        match self.rng.below(8) {
            0 => {
                e = format!(
                    "{e}.translate([{}, 0, 0])",
                    self.pick_str(&["-1.2", "1.2", "0.5"])
                )
            }
            1 => {
                e = format!(
                    "{e}.twist(axis: [0, 1, 0], rate: {})",
                    self.pick_str(&["0.5", "1", "-0.8"])
                )
            }
            2 => {
                e = format!(
                    "{e}.mirror({})",
                    self.pick_str(&["[1, 0, 0]", "normal: [0, 0, 1]"])
                )
            }
            3 => {
                e = format!(
                    "{e}.rotate_y({})",
                    self.pick_str(&["30deg", "90deg", "1rad"])
                )
            }
            4 => e = format!("{e}.scale({})", self.pick_str(&["1.5", "0.5"])),
            5 => e = format!("{e}.bend(rate: 0.3)"),
            6 if self.rng.chance(0.3) => {
                e = format!(
                    "{e}.{}",
                    self.pick_str(&["repeat(4)", "elongate([0.3, 0, 0])", "round(0.02)"])
                )
            }
            _ => {}
        }
        e
    }

    fn render(&mut self, tops: &[usize]) {
        // Mostly the derived shapes: they are what §5 is about.
        let derived: Vec<usize> = tops
            .iter()
            .copied()
            .filter(|&s| self.shapes[s].derived)
            .collect();
        // Half the time those without nested walks (an atlas on a displaced shape read
        // in the render is usually too large for a driver unrolled: E0118).
        let shallow: Vec<usize> = derived
            .iter()
            .copied()
            .filter(|&s| self.shapes[s].nest <= 1)
            .collect();
        let n = 1 + self.rng.below(3);
        let mut e = String::new();
        for i in 0..n {
            let s = if !shallow.is_empty() && self.rng.chance(0.4) {
                *self.rng.pick(&shallow)
            } else if !derived.is_empty() && self.rng.chance(0.75) {
                *self.rng.pick(&derived)
            } else {
                *self.rng.pick(tops)
            };
            let o = self.operand(s);
            if i == 0 {
                e = o;
                continue;
            }
            let k = self.pick_str(&["0.1", "0.3", "0.5"]);
            e = match self.rng.below(9) {
                0 | 1 => format!("{e} | {o}"),
                2 => format!("({e}) & {o}"),
                3 => format!("({e}) - {o}"),
                4 | 5 => format!("smooth_union({e}, {o}, {k})"),
                6 => format!("smooth_intersection({e}, {o}, {k})"),
                7 => format!("smooth_difference({e}, {o}, k: {k})"),
                _ => format!("union({e}, {o})"),
            };
        }
        if self.rng.chance(0.15) {
            e = format!("({e}).twist(rate: 0.4)");
        }
        if self.rng.chance(0.3) {
            self.items.push(format!("render {e};"));
            return;
        }
        let mut body = Vec::new();
        if self.rng.chance(0.6) {
            body.push(format!(
                "    camera = orbit(distance: {}, yaw: 20deg, pitch: 12deg);",
                self.pick_str(&["4", "6", "3.5"])
            ));
        }
        if self.rng.chance(0.5) {
            body.push("    light = sun(direction: [0.5, 0.8, 0.7]);".to_string());
        }
        if self.rng.chance(0.5) {
            body.push(format!(
                "    size = {};",
                self.pick_str(&["[64, 64]", "[320, 240]"])
            ));
        }
        self.items
            .push(format!("render {e} {{\n{}\n}}", body.join("\n")));
    }
}

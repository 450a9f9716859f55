//! The primitives' one home: for each primitive kind, its distance (the f64 CPU
//! reference), its bounds and Lipschitz constant, its cost in the guards' model, its
//! code and parameter record in unions evaluated as data, and its WGSL call (the
//! function of `shaders/sdf.wgsl` and its arguments). The lowering, the CPU
//! evaluator, the guards, the group tables and the WGSL writers all read these;
//! `tests/agreement.rs` checks the CPU against the GPU and the bounds and Lipschitz
//! constants against samples for every primitive.

use super::Aabb;
use glam::{DVec2, DVec3};

/// A primitive's distance function, in its local frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Prim {
    Sphere {
        r: f64,
    },
    Box {
        half: DVec3,
    },
    RoundBox {
        half: DVec3,
        r: f64,
    },
    BoxFrame {
        half: DVec3,
        e: f64,
    },
    Torus {
        major: f64,
        minor: f64,
    },
    Capsule {
        a: DVec3,
        b: DVec3,
        r: f64,
    },
    Cylinder {
        r: f64,
        half_h: f64,
    },
    /// A capped cone centred on the origin (IQ's sdCappedCone): half height, bottom and top radii.
    CappedCone {
        half_h: f64,
        r1: f64,
        r2: f64,
    },
    Plane {
        n: DVec3,
        offset: f64,
    },
    Ellipsoid {
        radii: DVec3,
    },
    Octahedron {
        s: f64,
    },
    HexPrism {
        r: f64,
        half_h: f64,
    },
    TriPrism {
        r: f64,
        half_h: f64,
    },
    Pyramid {
        h: f64,
    },
    Link {
        le: f64,
        r1: f64,
        r2: f64,
    },
}

/// How a primitive's parameter is laid out: in its WGSL call and its group record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Slot {
    /// One `f32`.
    Float,
    /// A `vec3<f32>` (three words).
    Vec3,
}

impl Slot {
    /// Its words in a group record (and floats in `Prim::params`).
    pub const fn words(self) -> usize {
        match self {
            Slot::Float => 1,
            Slot::Vec3 => 3,
        }
    }
}

/// The facts of a primitive kind that do not depend on its parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kind {
    /// The kind's code in group leaf records (`codegen::group` switches on it).
    pub code: u32,
    /// The distance function of `shaders/sdf.wgsl`.
    pub wgsl: &'static str,
    /// Its parameters after the point, in order (the group record's order too).
    pub slots: &'static [Slot],
    /// About how many sphere evaluations one evaluation costs (the guards' model).
    pub cost: f64,
    /// Its gradient by hand in `shaders/dual.wgsl` (`vec4(∇f, f)`, the same arguments),
    /// or None: differences of the primitive alone (`codegen::dual`).
    pub gradient: Option<&'static str>,
}

use Slot::{Float as F, Vec3 as V};

/// Every primitive kind, by code.
pub static KINDS: &[Kind] = &[
    kind(0, "sd_sphere", &[F], 1.0, Some("dsd_sphere")),
    kind(1, "sd_box", &[V], 1.5, Some("dsd_box")),
    kind(2, "sd_round_box", &[V, F], 1.5, Some("dsd_round_box")),
    kind(3, "sd_box_frame", &[V, F], 2.5, None),
    kind(4, "sd_torus", &[F, F], 1.5, Some("dsd_torus")),
    kind(5, "sd_capsule", &[V, V, F], 1.5, Some("dsd_capsule")),
    kind(6, "sd_cylinder", &[F, F], 1.5, Some("dsd_cylinder")),
    kind(7, "sd_capped_cone", &[F, F, F], 2.5, None),
    kind(8, "sd_plane", &[V, F], 1.0, Some("dsd_plane")),
    kind(9, "sd_ellipsoid", &[V], 1.5, Some("dsd_ellipsoid")),
    kind(10, "sd_octahedron", &[F], 2.5, None),
    kind(11, "sd_hex_prism", &[F, F], 2.5, None),
    kind(12, "sd_tri_prism", &[F, F], 1.5, Some("dsd_tri_prism")),
    kind(13, "sd_pyramid", &[F], 2.5, None),
    kind(14, "sd_link", &[F, F, F], 1.5, Some("dsd_link")),
];

const fn kind(
    code: u32,
    wgsl: &'static str,
    slots: &'static [Slot],
    cost: f64,
    gradient: Option<&'static str>,
) -> Kind {
    Kind {
        code,
        wgsl,
        slots,
        cost,
        gradient,
    }
}

/// A capsule's point `p` less the nearest point of its segment `a`–`b` (the capsule's
/// distance is its length less the radius; its gradient, `ir::dual`, its direction).
pub fn capsule_offset(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let (pa, ba) = (p - a, b - a);
    let bb = ba.dot(ba);
    let h = if bb > 0.0 {
        (pa.dot(ba) / bb).clamp(0.0, 1.0)
    } else {
        0.0
    };
    pa - ba * h
}

/// The signed distance to a centred box of half size `half` (`sd_box` in the shaders).
pub fn box_dist(p: DVec3, half: DVec3) -> f64 {
    let q = p.abs() - half;
    q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
}

impl Prim {
    /// The kind's code ([`KINDS`]'s index).
    pub fn code(&self) -> u32 {
        match self {
            Prim::Sphere { .. } => 0,
            Prim::Box { .. } => 1,
            Prim::RoundBox { .. } => 2,
            Prim::BoxFrame { .. } => 3,
            Prim::Torus { .. } => 4,
            Prim::Capsule { .. } => 5,
            Prim::Cylinder { .. } => 6,
            Prim::CappedCone { .. } => 7,
            Prim::Plane { .. } => 8,
            Prim::Ellipsoid { .. } => 9,
            Prim::Octahedron { .. } => 10,
            Prim::HexPrism { .. } => 11,
            Prim::TriPrism { .. } => 12,
            Prim::Pyramid { .. } => 13,
            Prim::Link { .. } => 14,
        }
    }

    /// The kind's facts.
    pub fn kind(&self) -> &'static Kind {
        &KINDS[self.code() as usize]
    }

    /// The parameters in [`Kind::slots`] order, a vec3 as three numbers: the WGSL
    /// call's arguments after the point, and the group record.
    pub fn params(&self) -> Vec<f64> {
        match *self {
            Prim::Sphere { r } => vec![r],
            Prim::Box { half } => half.to_array().to_vec(),
            Prim::RoundBox { half, r } | Prim::BoxFrame { half, e: r } => {
                vec![half.x, half.y, half.z, r]
            }
            Prim::Torus { major, minor } => vec![major, minor],
            Prim::Capsule { a, b, r } => vec![a.x, a.y, a.z, b.x, b.y, b.z, r],
            Prim::Cylinder { r, half_h }
            | Prim::HexPrism { r, half_h }
            | Prim::TriPrism { r, half_h } => vec![r, half_h],
            Prim::CappedCone { half_h, r1, r2 } => vec![half_h, r1, r2],
            Prim::Plane { n, offset } => vec![n.x, n.y, n.z, offset],
            Prim::Ellipsoid { radii } => radii.to_array().to_vec(),
            Prim::Octahedron { s } => vec![s],
            Prim::Pyramid { h } => vec![h],
            Prim::Link { le, r1, r2 } => vec![le, r1, r2],
        }
    }

    /// The primitive of the same kind with parameters `v` in [`Prim::params`]' order
    /// (its inverse); `None` when `v` is too short.
    pub fn with_params(&self, v: &[f64]) -> Option<Prim> {
        let at = |i: usize| v.get(i).copied();
        let v3 = |i: usize| Some(DVec3::new(at(i)?, at(i + 1)?, at(i + 2)?));
        Some(match *self {
            Prim::Sphere { .. } => Prim::Sphere { r: at(0)? },
            Prim::Box { .. } => Prim::Box { half: v3(0)? },
            Prim::RoundBox { .. } => Prim::RoundBox {
                half: v3(0)?,
                r: at(3)?,
            },
            Prim::BoxFrame { .. } => Prim::BoxFrame {
                half: v3(0)?,
                e: at(3)?,
            },
            Prim::Torus { .. } => Prim::Torus {
                major: at(0)?,
                minor: at(1)?,
            },
            Prim::Capsule { .. } => Prim::Capsule {
                a: v3(0)?,
                b: v3(3)?,
                r: at(6)?,
            },
            Prim::Cylinder { .. } => Prim::Cylinder {
                r: at(0)?,
                half_h: at(1)?,
            },
            Prim::HexPrism { .. } => Prim::HexPrism {
                r: at(0)?,
                half_h: at(1)?,
            },
            Prim::TriPrism { .. } => Prim::TriPrism {
                r: at(0)?,
                half_h: at(1)?,
            },
            Prim::CappedCone { .. } => Prim::CappedCone {
                half_h: at(0)?,
                r1: at(1)?,
                r2: at(2)?,
            },
            Prim::Plane { .. } => Prim::Plane {
                n: v3(0)?,
                offset: at(3)?,
            },
            Prim::Ellipsoid { .. } => Prim::Ellipsoid { radii: v3(0)? },
            Prim::Octahedron { .. } => Prim::Octahedron { s: at(0)? },
            Prim::Pyramid { .. } => Prim::Pyramid { h: at(0)? },
            Prim::Link { .. } => Prim::Link {
                le: at(0)?,
                r1: at(1)?,
                r2: at(2)?,
            },
        })
    }

    /// The WGSL call at point expression `p`, the numbers written by `float` and
    /// `vec3` (the generator's literal forms), but slot `i`'s written by `run_time(i)`
    /// where it gives one (a run-time value's expression).
    pub fn wgsl_call(
        &self,
        p: &str,
        float: impl Fn(f64) -> String,
        vec3: impl Fn(DVec3) -> String,
        run_time: impl Fn(usize, Slot) -> Option<String>,
    ) -> String {
        let params = self.params();
        let mut args = vec![p.to_string()];
        let mut at = 0;
        for (i, slot) in self.kind().slots.iter().enumerate() {
            let width = slot.words();
            let written = run_time(i, *slot).unwrap_or_else(|| match slot {
                Slot::Float => float(params[at]),
                Slot::Vec3 => vec3(DVec3::from_slice(&params[at..at + 3])),
            });
            args.push(written);
            at += width;
        }
        format!("{}({})", self.kind().wgsl, args.join(", "))
    }

    /// The bounds of the zero set (and of everything inside it) in the local frame.
    pub fn bounds(&self) -> Aabb {
        match self {
            Prim::Sphere { r } => Aabb::centered(DVec3::splat(*r)),
            Prim::Box { half } | Prim::RoundBox { half, .. } | Prim::BoxFrame { half, .. } => {
                Aabb::centered(*half)
            }
            Prim::Torus { major, minor } => {
                Aabb::centered(DVec3::new(major + minor, *minor, major + minor))
            }
            Prim::Capsule { a, b, r } => Aabb {
                min: a.min(*b),
                max: a.max(*b),
            }
            .expand(*r),
            Prim::Cylinder { r, half_h } => Aabb::centered(DVec3::new(*r, *half_h, *r)),
            Prim::CappedCone { half_h, r1, r2 } => {
                Aabb::centered(DVec3::new(r1.max(*r2), *half_h, r1.max(*r2)))
            }
            Prim::Plane { .. } => Aabb::INFINITE,
            Prim::Ellipsoid { radii } => Aabb::centered(*radii),
            Prim::Octahedron { s } => Aabb::centered(DVec3::splat(*s)),
            Prim::HexPrism { r, half_h } => Aabb::centered(DVec3::new(
                r * 1.154_700_538_379_251_5,
                r * 1.154_700_538_379_251_5,
                *half_h,
            )),
            Prim::TriPrism { r, half_h } => Aabb::centered(DVec3::new(r * 2.0, r * 2.0, *half_h)),
            Prim::Pyramid { h } => Aabb {
                min: DVec3::new(-0.5, 0.0, -0.5),
                max: DVec3::new(0.5, *h, 0.5),
            },
            Prim::Link { le, r1, r2 } => Aabb::centered(DVec3::new(r1 + r2, le + r1 + r2, *r2)),
        }
    }

    /// An upper bound of the distance's gradient: 1 for the exact distances; IQ's
    /// ellipsoid is a bound whose gradient can exceed 1 by the axis ratio.
    pub fn lipschitz(&self) -> f64 {
        match self {
            Prim::Ellipsoid { radii } => radii.max_element() / radii.min_element(),
            _ => 1.0,
        }
    }

    /// The signed distance at local point `p` (the f64 reference of the WGSL function).
    pub fn distance(&self, p: DVec3) -> f64 {
        match *self {
            Prim::Sphere { r } => p.length() - r,
            Prim::Box { half } => box_dist(p, half),
            Prim::RoundBox { half, r } => box_dist(p, half) - r,
            Prim::BoxFrame { half, e } => {
                let p = p.abs() - half;
                let q = (p + DVec3::splat(e)).abs() - DVec3::splat(e);
                let a = DVec3::new(p.x, q.y, q.z);
                let b = DVec3::new(q.x, p.y, q.z);
                let c = DVec3::new(q.x, q.y, p.z);
                let part = |v: DVec3| v.max(DVec3::ZERO).length() + v.max_element().min(0.0);
                part(a).min(part(b)).min(part(c))
            }
            Prim::Torus { major, minor } => {
                DVec2::new(DVec2::new(p.x, p.z).length() - major, p.y).length() - minor
            }
            Prim::Capsule { a, b, r } => capsule_offset(p, a, b).length() - r,
            Prim::Cylinder { r, half_h } => {
                let d =
                    DVec2::new(DVec2::new(p.x, p.z).length(), p.y).abs() - DVec2::new(r, half_h);
                d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
            }
            Prim::CappedCone { half_h: h, r1, r2 } => {
                let q = DVec2::new(DVec2::new(p.x, p.z).length(), p.y);
                let k1 = DVec2::new(r2, h);
                let k2 = DVec2::new(r2 - r1, 2.0 * h);
                let ca = DVec2::new(
                    q.x - q.x.min(if q.y < 0.0 { r1 } else { r2 }),
                    q.y.abs() - h,
                );
                let cb = q - k1 + k2 * ((k1 - q).dot(k2) / k2.dot(k2)).clamp(0.0, 1.0);
                let s = if cb.x < 0.0 && ca.y < 0.0 { -1.0 } else { 1.0 };
                s * ca.dot(ca).min(cb.dot(cb)).sqrt()
            }
            Prim::Plane { n, offset } => p.dot(n) - offset,
            Prim::Ellipsoid { radii } => {
                let k0 = (p / radii).length();
                let k1 = (p / (radii * radii)).length();
                if k1 == 0.0 {
                    -radii.min_element()
                } else {
                    k0 * (k0 - 1.0) / k1
                }
            }
            Prim::Octahedron { s } => {
                let p = p.abs();
                let m = p.x + p.y + p.z - s;
                let q = if 3.0 * p.x < m {
                    p
                } else if 3.0 * p.y < m {
                    DVec3::new(p.y, p.z, p.x)
                } else if 3.0 * p.z < m {
                    DVec3::new(p.z, p.x, p.y)
                } else {
                    return m * 0.577_350_269_189_625_8;
                };
                let k = (0.5 * (q.z - q.y + s)).clamp(0.0, s);
                DVec3::new(q.x, q.y - s + k, q.z - k).length()
            }
            Prim::HexPrism { r, half_h } => {
                let k = DVec3::new(-0.866_025_403_784_438_6, 0.5, 0.577_350_269_189_625_8);
                let mut p = p.abs();
                let kxy = DVec2::new(k.x, k.y);
                let pxy = DVec2::new(p.x, p.y) - 2.0 * kxy.dot(DVec2::new(p.x, p.y)).min(0.0) * kxy;
                p.x = pxy.x;
                p.y = pxy.y;
                let d = DVec2::new(
                    (DVec2::new(p.x, p.y) - DVec2::new(p.x.clamp(-k.z * r, k.z * r), r)).length()
                        * (p.y - r).signum(),
                    p.z - half_h,
                );
                d.x.max(d.y).min(0.0) + d.max(DVec2::ZERO).length()
            }
            Prim::TriPrism { r, half_h } => {
                let q = p.abs();
                (q.z - half_h).max((q.x * 0.866_025_403_784_438_6 + p.y * 0.5).max(-p.y) - r * 0.5)
            }
            Prim::Pyramid { h } => {
                // Below the base the nearest point is on the base square; IQ's formula
                // overestimates there.
                if p.y < 0.0 {
                    return DVec3::new((p.x.abs() - 0.5).max(0.0), p.y, (p.z.abs() - 0.5).max(0.0))
                        .length();
                }
                let m2 = h * h + 0.25;
                let (mut px, py, mut pz) = (p.x.abs(), p.y, p.z.abs());
                if pz > px {
                    std::mem::swap(&mut px, &mut pz);
                }
                px -= 0.5;
                pz -= 0.5;
                let q = DVec3::new(pz, h * py - 0.5 * px, h * px + 0.5 * py);
                let s = (-q.x).max(0.0);
                let t = ((q.y - 0.5 * pz) / (m2 + 0.25)).clamp(0.0, 1.0);
                let a = m2 * (q.x + s) * (q.x + s) + q.y * q.y;
                let b = m2 * (q.x + 0.5 * t) * (q.x + 0.5 * t) + (q.y - m2 * t) * (q.y - m2 * t);
                let d2 = if q.y.min(-q.x * m2 - q.y * 0.5) > 0.0 {
                    0.0
                } else {
                    a.min(b)
                };
                ((d2 + q.z * q.z) / m2).sqrt() * q.z.max(-py).signum()
            }
            Prim::Link { le, r1, r2 } => {
                let q = DVec3::new(p.x, (p.y.abs() - le).max(0.0), p.z);
                DVec2::new(DVec2::new(q.x, q.y).length() - r1, q.z).length() - r2
            }
        }
    }
}

//! Interval arithmetic over run-time parameters: for a value computed from parameters
//! ([`super::types::Uniform`]), an interval per component that holds for every value
//! the parameters may take in their declared ranges. Step bounds, bounding boxes and
//! the checks on arguments read these intervals, so sphere tracing stays safe whatever
//! value a slider takes.
//!
//! The rules follow the f64 meaning of each operator and math builtin
//! ([`super::math`]): for functions monotone in each argument (or multilinear, like
//! `mix`) the extremes lie at the corners of the argument box; periodic and folded
//! functions (`sin`, `abs`, `fract`) have rules of their own. A result that cannot be
//! bounded is `(-∞, ∞)`.

use super::math::Math;
use crate::syntax::ast::BinaryOp;

/// A closed interval `[lo, hi]` (possibly infinite).
pub type Iv = (f64, f64);

/// The whole line: what cannot be bounded.
pub const UNBOUNDED: Iv = (f64::NEG_INFINITY, f64::INFINITY);

/// The hull of some values; unbounded when one is NaN.
fn hull(values: impl IntoIterator<Item = f64>) -> Iv {
    let mut out = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        if v.is_nan() {
            return UNBOUNDED;
        }
        out = (out.0.min(v), out.1.max(v));
    }
    out
}

/// A product of interval ends where `0 · ∞` is 0 (the ends are limits).
fn mul_end(a: f64, b: f64) -> f64 {
    if a == 0.0 || b == 0.0 {
        0.0
    } else {
        a * b
    }
}

fn mul(a: Iv, b: Iv) -> Iv {
    hull([
        mul_end(a.0, b.0),
        mul_end(a.0, b.1),
        mul_end(a.1, b.0),
        mul_end(a.1, b.1),
    ])
}

fn div(a: Iv, b: Iv) -> Iv {
    if b.0 <= 0.0 && b.1 >= 0.0 {
        return UNBOUNDED;
    }
    mul(a, (1.0 / b.1, 1.0 / b.0))
}

/// `a − b·floor(a / b)`: within [0, b) for positive b, (b, 0] for negative.
fn rem(a: Iv, b: Iv) -> Iv {
    if a.0 == a.1 && b.0 == b.1 {
        let r = super::math::arithmetic(BinaryOp::Rem, a.0, b.0).unwrap_or(f64::NAN);
        return hull([r]);
    }
    if b.0 > 0.0 {
        (0.0, b.1)
    } else if b.1 < 0.0 {
        (b.0, 0.0)
    } else {
        let m = b.0.abs().max(b.1.abs());
        (-m, m)
    }
}

/// Broadcasts two component lists (a float meets a vector) through `f`.
fn zip(a: &[Iv], b: &[Iv], f: impl Fn(Iv, Iv) -> Iv) -> Vec<Iv> {
    let n = a.len().max(b.len());
    let get = |v: &[Iv], i: usize| v[i.min(v.len() - 1)];
    (0..n).map(|i| f(get(a, i), get(b, i))).collect()
}

/// An arithmetic operator on intervals (`+ - * / %`); `None` for the others.
pub fn binary(op: BinaryOp, a: &[Iv], b: &[Iv]) -> Option<Vec<Iv>> {
    use BinaryOp::*;
    let f: fn(Iv, Iv) -> Iv = match op {
        Add => |a, b| hull([a.0 + b.0, a.1 + b.1]),
        Sub => |a, b| hull([a.0 - b.1, a.1 - b.0]),
        Mul => mul,
        Div => div,
        Rem => rem,
        _ => return None,
    };
    Some(zip(a, b, f))
}

/// `-a`.
pub fn neg(a: &[Iv]) -> Vec<Iv> {
    a.iter().map(|&(lo, hi)| (-hi, -lo)).collect()
}

/// The extremes of `f` over the corners of a box of scalar intervals: exact for
/// functions monotone in each argument, and for multilinear ones.
fn corners(args: &[Iv], f: impl Fn(&[f64]) -> f64) -> Iv {
    let n = args.len();
    let mut point = vec![0.0; n];
    hull((0..1usize << n).map(|mask| {
        for (i, a) in args.iter().enumerate() {
            point[i] = if mask >> i & 1 == 0 { a.0 } else { a.1 };
        }
        f(&point)
    }))
}

/// `sin` over an interval: the ends, and the extremes ±1 where a peak lies inside.
fn sin(a: Iv) -> Iv {
    // A full period or more (NaN and infinite widths included).
    let width = a.1 - a.0;
    if width.is_nan() || width >= std::f64::consts::TAU {
        return (-1.0, 1.0);
    }
    let (mut lo, mut hi) = hull([a.0.sin(), a.1.sin()]);
    let half_pi = std::f64::consts::FRAC_PI_2;
    // Peaks at π/2 + kπ: +1 for even k, −1 for odd.
    let first = ((a.0 - half_pi) / std::f64::consts::PI).ceil();
    let mut k = first;
    while half_pi + k * std::f64::consts::PI <= a.1 {
        if (k as i64).rem_euclid(2) == 0 {
            hi = 1.0;
        } else {
            lo = -1.0;
        }
        k += 1.0;
    }
    (lo, hi)
}

fn abs(a: Iv) -> Iv {
    if a.0 >= 0.0 {
        a
    } else if a.1 <= 0.0 {
        (-a.1, -a.0)
    } else {
        (0.0, (-a.0).max(a.1))
    }
}

/// The smallest |x| over an interval.
fn min_abs(a: Iv) -> f64 {
    if a.0 <= 0.0 && a.1 >= 0.0 {
        0.0
    } else {
        a.0.abs().min(a.1.abs())
    }
}

/// A math builtin on intervals (arguments as components, floats widened to the call's
/// size `n` where the builtin widens), per [`super::math::MATH`]'s meaning.
pub fn math(m: Math, args: &[Vec<Iv>], n: usize) -> Vec<Iv> {
    let arg = |i: usize, c: usize| -> Iv {
        let a = &args[i];
        a[c.min(a.len() - 1)]
    };
    let per = |f: &dyn Fn(usize) -> Iv| (0..n).map(f).collect::<Vec<Iv>>();
    let f = |m: Math| {
        move |x: &[f64]| -> f64 {
            let comps: Vec<[f64; 1]> = x.iter().map(|&v| [v]).collect();
            let refs: Vec<&[f64]> = comps.iter().map(|c| c.as_slice()).collect();
            m.eval(&refs)[0]
        }
    };
    let by_corners = |m: Math| {
        per(&|c| {
            corners(
                &(0..args.len()).map(|i| arg(i, c)).collect::<Vec<_>>(),
                f(m),
            )
        })
    };
    match m {
        // Monotone in each argument, or multilinear (mix).
        Math::Asin
        | Math::Acos
        | Math::Atan
        | Math::Sqrt
        | Math::Floor
        | Math::Ceil
        | Math::Sign
        | Math::Exp
        | Math::Log
        | Math::Min
        | Math::Max
        | Math::Clamp
        | Math::Mix
        | Math::Step
        | Math::Radians
        | Math::Degrees => by_corners(m),
        Math::Sin => per(&|c| sin(arg(0, c))),
        Math::Cos => per(&|c| {
            let a = arg(0, c);
            let half_pi = std::f64::consts::FRAC_PI_2;
            sin((a.0 + half_pi, a.1 + half_pi))
        }),
        Math::Tan => per(&|c| {
            // Monotone between its poles at π/2 + kπ.
            let a = arg(0, c);
            let pi = std::f64::consts::PI;
            let k = ((a.0 - std::f64::consts::FRAC_PI_2) / pi).ceil();
            if std::f64::consts::FRAC_PI_2 + k * pi <= a.1 || !a.1.is_finite() {
                UNBOUNDED
            } else {
                corners(&[a], f(m))
            }
        }),
        Math::Atan2 => per(&|c| {
            let (y, x) = (arg(0, c), arg(1, c));
            if y.0 == y.1 && x.0 == x.1 {
                hull([y.0.atan2(x.0)])
            } else {
                (-std::f64::consts::PI, std::f64::consts::PI)
            }
        }),
        Math::Abs => per(&|c| abs(arg(0, c))),
        Math::Fract => per(&|c| {
            let a = arg(0, c);
            if a.0.is_finite() && a.0.floor() == a.1.floor() {
                (super::math::fract(a.0), super::math::fract(a.1))
            } else {
                (0.0, 1.0)
            }
        }),
        Math::Pow => per(&|c| {
            let (x, y) = (arg(0, c), arg(1, c));
            // Monotone in each argument where the base is positive.
            if x.0 > 0.0 {
                corners(&[x, y], f(m))
            } else if x.0 == x.1 && y.0 == y.1 {
                hull([x.0.powf(y.0)])
            } else {
                UNBOUNDED
            }
        }),
        Math::Smoothstep => per(&|c| {
            let (e0, e1, x) = (arg(0, c), arg(1, c), arg(2, c));
            if e0.0 == e0.1 && e1.0 == e1.1 && e0.0 < e1.0 {
                corners(&[e0, e1, x], f(m))
            } else {
                (0.0, 1.0)
            }
        }),
        Math::Length | Math::Distance => {
            let comps: Vec<Iv> = if m == Math::Length {
                args[0].clone()
            } else {
                zip(&args[0], &args[1], |a, b| hull([a.0 - b.1, a.1 - b.0]))
            };
            let lo = comps
                .iter()
                .map(|&a| min_abs(a).powi(2))
                .sum::<f64>()
                .sqrt();
            let hi = comps
                .iter()
                .map(|&a| a.0.abs().max(a.1.abs()).powi(2))
                .sum::<f64>()
                .sqrt();
            vec![(lo, hi)]
        }
        Math::Dot => {
            let products = zip(&args[0], &args[1], mul);
            vec![products
                .iter()
                .fold((0.0, 0.0), |s, p| (s.0 + p.0, s.1 + p.1))]
        }
        Math::Cross => {
            let (a, b) = (&args[0], &args[1]);
            let term = |i: usize, j: usize| {
                let (p, q) = (mul(a[i], b[j]), mul(a[j], b[i]));
                hull([p.0 - q.1, p.1 - q.0])
            };
            vec![term(1, 2), term(2, 0), term(0, 1)]
        }
        Math::Normalize => per(&|_| (-1.0, 1.0)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Samples `f` densely over the box and checks the interval holds every sample.
    fn holds(iv: Iv, samples: impl Iterator<Item = f64>) {
        for s in samples {
            assert!(s >= iv.0 - 1e-12 && s <= iv.1 + 1e-12, "{s} outside {iv:?}");
        }
    }

    #[test]
    fn sin_and_cos_hold_and_are_tight() {
        for &(a, b) in &[(0.0, 1.0), (1.0, 2.0), (-4.0, 0.5), (2.0, 9.0), (0.0, 0.0)] {
            let s = math(Math::Sin, &[vec![(a, b)]], 1)[0];
            let c = math(Math::Cos, &[vec![(a, b)]], 1)[0];
            let xs = (0..=1000).map(|i| a + (b - a) * i as f64 / 1000.0);
            holds(s, xs.clone().map(f64::sin));
            holds(c, xs.clone().map(f64::cos));
            // Tight: the ends are reached to within the sampling.
            let lo = xs.clone().map(f64::sin).fold(f64::INFINITY, f64::min);
            assert!((s.0 - lo).abs() < 1e-5, "{s:?} {lo}");
        }
    }

    #[test]
    fn arithmetic_holds_over_samples() {
        let (a, b) = ((-1.0, 2.0), (0.5, 3.0));
        let grid = |iv: Iv| (0..=20).map(move |i| iv.0 + (iv.1 - iv.0) * i as f64 / 20.0);
        for op in [
            BinaryOp::Add,
            BinaryOp::Sub,
            BinaryOp::Mul,
            BinaryOp::Div,
            BinaryOp::Rem,
        ] {
            let iv = binary(op, &[a], &[b]).unwrap()[0];
            for x in grid(a) {
                holds(
                    iv,
                    grid(b).map(|y| super::super::math::arithmetic(op, x, y).unwrap()),
                );
            }
        }
        assert_eq!(
            binary(BinaryOp::Div, &[a], &[(-1.0, 1.0)]).unwrap()[0],
            UNBOUNDED
        );
    }

    #[test]
    fn unbounded_time_stays_unbounded_until_bounded() {
        let time = (0.0, f64::INFINITY);
        assert_eq!(
            binary(BinaryOp::Mul, &[time], &[(2.0, 2.0)]).unwrap()[0].1,
            f64::INFINITY
        );
        assert_eq!(math(Math::Sin, &[vec![time]], 1)[0], (-1.0, 1.0));
        assert_eq!(math(Math::Fract, &[vec![time]], 1)[0], (0.0, 1.0));
        let c = math(
            Math::Clamp,
            &[vec![time], vec![(0.0, 0.0)], vec![(10.0, 10.0)]],
            1,
        )[0];
        assert_eq!(c, (0.0, 10.0));
    }
}

//! Implicit shell maps (§5.4 of the Implicit UVs paper, Eq. 60–62).
//!
//! `base.shell_map(tile, uv, thickness: ε, base: keep)` copies the tile shape g into the
//! ε-shell M^ε = {|f| ≤ ε} of the base surface. A point x of the shell has shell
//! coordinates
//!
//!   S(x) = (fract(u) − 0.5, f(x)/ε, fract(v) − 0.5),   (u, v) = uv(Π_f(x)),
//!
//! (the paper's (u, v, f/ε), with the tile's "up" along y and the `fract` repetition
//! of Fig. 13 row C), so one tile cell of the uv spans x, z ∈ [−0.5, 0.5] and the
//! shell's thickness y ∈ [−1, 1]. The tile's part of the field is
//!
//!   t(x) = max(s · g(S(x)), b(f(x))),   b(f) = max(f − ε·hi, ε·lo − f),
//!
//! the tile clipped to its extent [lo, hi] ⊂ [−1, 1] in shell height (from the tile's
//! bound): b is a lower bound of the distance to anything there. Beyond [BAND] · ε of
//! that extent (where the uv are not even computed) t is b alone, which is then at
//! least BAND · ε, so rays do not stop on the band's edge (Eq. 58's τ). The result is
//! min(f, t) with `base` (Eq. 62), else t.
//!
//! **Limits.** Where the shell is thicker than the base's radius of curvature (a
//! rounded rim thinner than ε), Π_f stretches without bound near the medial axis and
//! the step bound below does not hold; keep ε below the smallest radius of curvature
//! the tiles cover.
//!
//! **Step bound.** S's Jacobian has norm at most √((k·c)² + (L_f/ε)²), where c bounds
//! the uv field's slope per unit of surface, k = [`STRETCH`] allows for the atlas's
//! metric distortion, and L_f is the base's Lipschitz bound. The tile's distance is
//! scaled by s = min(1 / (k·c), ε) so it stays near a distance, and the shell's bound
//! is max(L_f, L_g · s · √((k·c)² + (L_f/ε)²)). As with `repeat`, the tile must stay
//! inside its cell: `fract` jumps at the cell's borders.

use super::displace::{Height, Heights, STRETCH};
use glam::DVec3;

/// A shell map's constants.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellMap {
    /// The uv field (a vec2 [`Height`], read at Π_f(x)).
    pub uv: Height,
    /// ε.
    pub thickness: f64,
    /// Keep the base surface (min(f, t)).
    pub keep_base: bool,
    /// s: the tile's distance scale.
    pub scale: f64,
    /// The tile's extent in shell height (its bound's y range, within [−1, 1]): the
    /// tiles lie where ε·lo ≤ f ≤ ε·hi.
    pub lo: f64,
    pub hi: f64,
}

/// How far beyond the tiles' extent, in units of ε, the exact field is evaluated (τ
/// of Eq. 58): outside, the distance bound is at least BAND·ε, so rays never stop on
/// the band's edge.
pub const BAND: f64 = 0.5;

impl ShellMap {
    /// `tile_y`: the tile's bound along y (infinite for unbounded tiles).
    pub fn new(uv: Height, thickness: f64, keep_base: bool, tile_y: (f64, f64)) -> ShellMap {
        let c = (STRETCH * uv.slope).max(1e-9);
        ShellMap {
            scale: (1.0 / c).min(thickness),
            uv,
            thickness,
            keep_base,
            lo: tile_y.0.clamp(-1.0, 1.0),
            hi: tile_y.1.clamp(-1.0, 1.0),
        }
    }

    /// A lower bound of the distance to the tiles from where the base's field is `f`:
    /// they lie within ε·lo ≤ f ≤ ε·hi, and f is a distance.
    pub fn bound(&self, f: f64) -> f64 {
        (f - self.thickness * self.hi).max(self.thickness * self.lo - f)
    }

    /// Whether the exact field is evaluated where the base's field is `f`.
    pub fn in_band(&self, f: f64) -> bool {
        f < self.thickness * (self.hi + BAND) && f > self.thickness * (self.lo - BAND)
    }

    /// The Lipschitz bound of the shell-mapped field over a base of bound `base` and a
    /// tile of bound `tile`.
    pub fn lipschitz(&self, base: f64, tile: f64) -> f64 {
        let c = STRETCH * self.uv.slope;
        let j = (c * c + (base / self.thickness).powi(2)).sqrt();
        base.max(tile * self.scale * j)
    }

    /// The shell coordinates S(x) from the base's f at x and the uv at Π_f(x).
    pub fn coords(&self, f: f64, uv: glam::DVec2) -> DVec3 {
        let fr = |x: f64| x - x.floor() - 0.5;
        DVec3::new(fr(uv.x), f / self.thickness, fr(uv.y))
    }

    /// The field from the base's (distance, material) at x, the projection (computed
    /// only inside the shell) and the tile's evaluation at shell coordinates; the
    /// material is the tile's where the tile is nearer. `heights` evaluates the uv.
    pub fn field<M: Copy>(
        &self,
        f: (f64, M),
        project: impl FnOnce() -> (DVec3, DVec3),
        tile: impl FnOnce(DVec3) -> (f64, M),
        heights: &dyn Heights,
    ) -> (f64, M) {
        let bound = self.bound(f.0);
        let t = if !self.in_band(f.0) {
            (bound, f.1)
        } else {
            let (q, n) = project();
            match heights.uv(&self.uv, q, n) {
                Some(uv) => {
                    let (g, m) = tile(self.coords(f.0, uv));
                    ((self.scale * g).max(bound), m)
                }
                // Not given (no atlas or textures in `heights`): no tiles.
                None => (f64::INFINITY, f.1),
            }
        };
        if !self.keep_base || t.0 < f.0 {
            t
        } else {
            f
        }
    }
}

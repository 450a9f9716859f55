//! Atlases on moving shapes: an atlas whose own shape depends on run-time parameters
//! keeps its seeds (projected positions, solved frames, uv offsets), its merge graph's
//! edge lengths and its σ in the `tables` buffer, at offsets fixed when the module is
//! generated. When a parameter changes, the host recomputes that geometry on the f64
//! CPU reference at the new values ([`Module::tables_at`]: the shape's run-time numbers
//! rewritten, then the atlas prepared as the compiler prepares it) and uploads the
//! words; the WGSL is never generated again. Such an atlas scans its seeds without the
//! seed grid and walks unpruned: both depend on where the seeds lie.

use super::Module;
use crate::ir::dynamic::Values;
use crate::sema::AtlasDef;
use crate::uv::atlas::PrepareError;
use crate::uv::Atlas;

/// Words per seed record in the `tables` buffer: position, normal and e1 (3 each),
/// then the uv offset (2).
pub const SEED_WORDS: usize = 11;

/// Where an atlas's records lie in the `tables` buffer (word offsets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SeedsAt {
    /// [`SEED_WORDS`] per seed.
    pub seeds: u32,
    /// One start per seed and the end (CSR).
    pub adj_start: u32,
    /// `capacity` neighbour entries.
    pub adj: u32,
    /// `capacity` edge lengths.
    pub adj_d: u32,
    /// σ of the blend, when it lives in the buffer (moving atlases).
    pub sigma: Option<u32>,
    /// Room for this many adjacency entries (a moving atlas's: two per declared merge,
    /// the most any values can give; the graph only loses edges, never gains).
    pub capacity: u32,
    pub count: u32,
}

/// The merge graph's adjacency as CSR: starts (one per seed, and the end), neighbours
/// and edge lengths.
pub fn adjacency(atlas: &Atlas) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
    let mut start = vec![0u32];
    let (mut adj, mut adj_d) = (Vec::new(), Vec::new());
    for list in &atlas.graph.neighbors {
        for &(j, d) in list {
            adj.push(j as u32);
            adj_d.push(d);
        }
        start.push(adj.len() as u32);
    }
    (start, adj, adj_d)
}

/// Reserves the records of `atlas` at the end of `words` (room for `capacity`
/// adjacency entries, and σ when `sigma`) and writes them.
pub fn reserve(atlas: &Atlas, capacity: usize, sigma: bool, words: &mut Vec<u32>) -> SeedsAt {
    let n = atlas.seeds.len();
    let capacity = capacity.max(adjacency(atlas).1.len());
    let base = words.len() as u32;
    let at = SeedsAt {
        seeds: base,
        adj_start: base + (SEED_WORDS * n) as u32,
        adj: base + (SEED_WORDS * n + n + 1) as u32,
        adj_d: base + (SEED_WORDS * n + n + 1 + capacity) as u32,
        sigma: sigma.then_some(base + (SEED_WORDS * n + n + 1 + 2 * capacity) as u32),
        capacity: capacity as u32,
        count: n as u32,
    };
    words.resize(
        base as usize + SEED_WORDS * n + n + 1 + 2 * capacity + usize::from(sigma),
        0,
    );
    // Written just now with room for the whole graph: this cannot fail.
    let _ = write(atlas, &at, words);
    at
}

/// Writes `atlas`'s records at `at`; an error (and nothing written) when the atlas does
/// not fit the room reserved.
pub fn write(atlas: &Atlas, at: &SeedsAt, words: &mut [u32]) -> Result<(), String> {
    let (start, adj, adj_d) = adjacency(atlas);
    let end = at.sigma.map_or(at.adj_d + at.capacity, |s| s + 1) as usize;
    if atlas.seeds.len() != at.count as usize || adj.len() > at.capacity as usize {
        return Err(format!(
            "{} seeds and {} merge entries do not fit the room for {} and {}",
            atlas.seeds.len(),
            adj.len(),
            at.count,
            at.capacity
        ));
    }
    if end > words.len() {
        return Err(String::from("the tables buffer is too short"));
    }
    let f = |v: f64| (v as f32).to_bits();
    for (i, s) in atlas.seeds.iter().enumerate() {
        let (p, n, e1) = (s.seed.p, s.seed.n, s.seed.e1);
        let record = [
            p.x, p.y, p.z, n.x, n.y, n.z, e1.x, e1.y, e1.z, s.offset.x, s.offset.y,
        ];
        let o = at.seeds as usize + SEED_WORDS * i;
        for (w, v) in words[o..o + SEED_WORDS].iter_mut().zip(record) {
            *w = f(v);
        }
    }
    words[at.adj_start as usize..][..start.len()].copy_from_slice(&start);
    let cap = at.capacity as usize;
    let (a, d) = (at.adj as usize, at.adj_d as usize);
    words[a..a + cap].fill(0);
    words[d..d + cap].fill(0);
    words[a..a + adj.len()].copy_from_slice(&adj);
    for (w, v) in words[d..d + adj_d.len()].iter_mut().zip(adj_d) {
        *w = f(v);
    }
    if let Some(s) = at.sigma {
        words[s as usize] = f(atlas.sigma);
    }
    Ok(())
}

/// An atlas of the module whose shape depends on run-time parameters: what
/// recomputing its geometry needs.
#[derive(Debug, Clone)]
pub struct MovingAtlas {
    /// The atlas's index in the program (`atlas_K` in the module).
    pub index: usize,
    pub def: AtlasDef,
    /// The atlas as the module was generated (at the parameters' current values): its
    /// shape (with the run-time numbers' slots) and its heights' environment.
    pub atlas: Atlas,
    pub at: SeedsAt,
}

/// Why an atlas's geometry could not be recomputed at some parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct MovingError {
    pub atlas: String,
    pub reason: String,
}

impl std::fmt::Display for MovingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "atlas `{}` cannot follow these parameter values: {}",
            self.atlas, self.reason
        )
    }
}

impl std::error::Error for MovingError {}

impl MovingAtlas {
    /// The atlas prepared again on its shape at `values` (as the compiler prepares
    /// it: seed projections, frames, merge walks, offsets, σ).
    pub fn at_params(&self, values: Values) -> Result<Atlas, MovingError> {
        let error = |reason: String| MovingError {
            atlas: self.def.name.clone(),
            reason,
        };
        let shape = self
            .atlas
            .shape
            .at_params(values)
            .ok_or_else(|| error(String::from("a run-time number is not a number")))?;
        match Atlas::prepare_in(&self.def, &shape, self.atlas.heights.clone()) {
            Ok(mut a) => {
                a.rest = self.atlas.rest.clone();
                Ok(a)
            }
            Err(PrepareError::SeedOffSurface { seed }) => Err(error(format!(
                "seed `{}` cannot be projected onto its surface",
                self.def.seeds.get(seed).map_or("?", |s| s.name.as_str())
            ))),
        }
    }
}

impl Module {
    /// Whether some atlas of the module follows run-time parameters (its tables then
    /// change with them: [`Module::tables_at`]).
    pub fn has_moving_atlases(&self) -> bool {
        !self.moving.is_empty()
    }

    /// The `tables` buffer's words at parameter values `values` (by name; `None`: the
    /// module's default): the manifest's words with every moving atlas's records
    /// recomputed. A host uploads them with the parameters' block.
    pub fn tables_at(&self, values: Values) -> Result<Vec<u32>, MovingError> {
        let mut words = self.manifest.tables.clone();
        self.write_tables_at(values, &mut words)?;
        Ok(words)
    }

    /// What the moving atlases' geometry depends on at `values`: the values of the
    /// parameters their shapes read (by name, in order; `None`: the default). Equal
    /// keys give equal tables, so a host recomputes only when the key changes (not at
    /// every frame of `time` when no moving shape reads it).
    pub fn moving_key(&self, values: Values) -> Vec<u8> {
        let names: std::collections::BTreeSet<String> = self
            .moving
            .iter()
            .flat_map(|m| m.atlas.shape.param_names())
            .collect();
        let mut key = Vec::new();
        for name in names {
            key.extend_from_slice(name.as_bytes());
            key.push(0);
            for x in values(&name).unwrap_or_default() {
                key.extend_from_slice(&x.to_bits().to_le_bytes());
            }
            key.push(0xff);
        }
        key
    }

    /// [`Module::tables_at`] into `words` (the manifest's words, or an earlier
    /// result): only the moving atlases' records are written. Nothing is written
    /// when one atlas cannot be prepared at `values` (every atlas is prepared before
    /// any is written; writing fails only on a layout that does not fit, which the
    /// generator rules out).
    pub fn write_tables_at(&self, values: Values, words: &mut [u32]) -> Result<(), MovingError> {
        let atlases = self
            .moving
            .iter()
            .map(|m| m.at_params(values))
            .collect::<Result<Vec<_>, _>>()?;
        for (m, a) in self.moving.iter().zip(&atlases) {
            write(a, &m.at, words).map_err(|reason| MovingError {
                atlas: m.def.name.clone(),
                reason,
            })?;
        }
        Ok(())
    }
}

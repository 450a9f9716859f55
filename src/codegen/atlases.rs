//! The generator's loop over the prepared atlases: each atlas's code from the atlas
//! template ([`super::atlas`]), and which of them move with run-time parameters
//! ([`super::moving`]: those keep their records in the `tables` buffer, without the
//! seed grid).

use super::moving::MovingAtlas;
use super::{atlas, template, Definition, Generator, Options};
use crate::uv::Atlas;

impl Generator<'_> {
    /// Every prepared atlas's code, from the atlas template.
    pub(super) fn atlases(
        &mut self,
        atlases: &[Option<Atlas>],
        options: &Options,
    ) -> Result<(), template::Mismatch> {
        for (k, (prepared, def)) in atlases.iter().zip(&self.program.atlases).enumerate() {
            let Some(a) = prepared else { continue };
            let start = self.out.len();
            // An atlas on a moving shape: its seeds are rewritten by the host, so it
            // scans them without the grid, with room for every declared merge.
            let moving = a.shape.is_dynamic().then_some(2 * def.merges.len());
            let grid = match moving {
                Some(_) => crate::uv::grid::SeedGrid::single(a.seeds.len()),
                None => options.seed_grid.grid(a),
            };
            let (code, at) = atlas::emit(
                k,
                a,
                &grid,
                options,
                &mut self.tables,
                &mut self.groups,
                moving,
            )?;
            if let (Some(_), Some(at)) = (moving, at) {
                self.moving.push(MovingAtlas {
                    index: k,
                    def: def.clone(),
                    atlas: a.clone(),
                    at,
                });
            }
            self.out.push_str(&code);
            self.out.push_str(&atlas::at(k, a));
            self.region(start, Some(def.span), Definition::Atlas(def.name.clone()));
        }
        Ok(())
    }
}

//! The in-process pipeline cache: pipelines (with the layouts their bind groups need)
//! keyed by everything they were built from (the WGSL text, the entry point, the binding
//! table and the target formats), so that building the same module again (the viewer
//! reloading a file whose edit left the generated WGSL unchanged, a view toggled back,
//! repeated queries in the baker and the tests) costs a lookup instead of a shader
//! compilation.
//!
//! The key holds the whole WGSL text, not only its hash, so two modules can never share
//! a pipeline by a hash collision. The cache keeps the [`CAPACITY`] most recently used
//! pipelines; only pipelines created without a device error are stored.
//!
//! Across processes, the drivers keep their own caches (Mesa's shader cache in
//! `~/.cache/mesa_shader_cache`, NVIDIA's in `~/.nv`), which already make a second
//! `sdfc render` of the same scene start warm; see docs/performance.md.

use std::any::Any;
use std::path::PathBuf;
use std::sync::Mutex;

/// The most pipelines kept.
pub const CAPACITY: usize = 16;

struct Entry {
    key: String,
    value: Box<dyn Any + Send + Sync>,
}

/// Pipelines by what they were built from, most recently used first.
#[derive(Default)]
pub struct Pipelines {
    entries: Mutex<Vec<Entry>>,
}

impl Pipelines {
    /// The cached value of `key`, or `make()`'s (stored when it succeeds, and then the
    /// driver's cache `disk` saved), with whether it came from the cache.
    pub fn get_or_try<T, E>(
        &self,
        disk: Option<&Disk>,
        key: String,
        make: impl FnOnce() -> Result<T, E>,
    ) -> Result<(T, bool), E>
    where
        T: Clone + Send + Sync + 'static,
    {
        if let Some(v) = self.lookup::<T>(&key) {
            return Ok((v, true));
        }
        // Built outside the lock: a pipeline can take seconds.
        let value = make()?;
        if let Some(disk) = disk {
            disk.save();
        }
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        entries.retain(|e| e.key != key);
        entries.insert(
            0,
            Entry {
                key,
                value: Box::new(value.clone()),
            },
        );
        entries.truncate(CAPACITY);
        Ok((value, false))
    }

    fn lookup<T: Clone + 'static>(&self, key: &str) -> Option<T> {
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        let i = entries.iter().position(|e| e.key == key)?;
        let entry = entries.remove(i);
        let value = entry.value.downcast_ref::<T>().cloned();
        entries.insert(0, entry);
        value
    }

    /// How many pipelines are kept.
    pub fn len(&self) -> usize {
        self.entries.lock().unwrap_or_else(|e| e.into_inner()).len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Forgets every pipeline (`sdfc bench` measures real builds).
    pub fn clear(&self) {
        self.entries
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clear();
    }
}

/// The key of a pipeline: its kind and entry point, the description of its layouts and
/// targets, and the WGSL text.
pub fn key(kind: &str, layout: impl std::fmt::Debug, wgsl: &str) -> String {
    format!("{kind}\u{0}{layout:?}\u{0}{wgsl}")
}

/// The environment variable naming the folder of the on-disk pipeline cache.
pub const DISK_VAR: &str = "SDFC_PIPELINE_CACHE";

/// wgpu's pipeline cache (the driver's compiled pipelines, Vulkan only), kept on disk
/// between processes when `SDFC_PIPELINE_CACHE` names a folder. Opt-in: the driver
/// trusts the file's contents beyond its header, so a damaged file could bring the
/// driver down, and the drivers keep caches of their own.
pub struct Disk {
    pub cache: wgpu::PipelineCache,
    path: PathBuf,
}

impl Disk {
    /// The cache of `device`, loaded from the folder of `SDFC_PIPELINE_CACHE` when the
    /// backend supports one (`features` holds `PIPELINE_CACHE`).
    pub fn open(
        device: &wgpu::Device,
        info: &wgpu::AdapterInfo,
        features: wgpu::Features,
    ) -> Option<Disk> {
        let dir = std::env::var_os(DISK_VAR).filter(|d| !d.is_empty())?;
        if !features.contains(wgpu::Features::PIPELINE_CACHE) {
            return None;
        }
        let name = wgpu::util::pipeline_cache_key(info)?;
        let path = PathBuf::from(dir).join(format!("{name}.bin"));
        let data = std::fs::read(&path).ok();
        // SAFETY: the data, when there is any, is what `get_data` of this adapter's
        // cache returned (written by `save` below); wgpu and the driver check its
        // header and fall back to an empty cache when it does not match.
        let cache = unsafe {
            device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                label: Some("sdfc"),
                data: data.as_deref(),
                fallback: true,
            })
        };
        Some(Disk { cache, path })
    }

    /// Writes the cache's data to its file (atomically), after new pipelines.
    pub fn save(&self) {
        let Some(data) = self.cache.get_data() else {
            return;
        };
        if let Some(dir) = self.path.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        if let Err(e) = crate::fsutil::write_output(&self.path, &data) {
            eprintln!(
                "warning: cannot write the pipeline cache {}: {e}",
                self.path.display()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_misses_failures_and_eviction() {
        let cache = Pipelines::default();
        let made = std::cell::Cell::new(0);
        let make = |v: u32| {
            made.set(made.get() + 1);
            Ok::<u32, ()>(v)
        };
        assert_eq!(
            cache.get_or_try(None, key("r", 1, "a"), || make(1)),
            Ok((1, false))
        );
        assert_eq!(
            cache.get_or_try(None, key("r", 1, "a"), || make(9)),
            Ok((1, true))
        );
        // Another layout, kind or text is another pipeline.
        assert_eq!(
            cache.get_or_try(None, key("r", 2, "a"), || make(2)),
            Ok((2, false))
        );
        assert_eq!(
            cache.get_or_try(None, key("c", 1, "a"), || make(3)),
            Ok((3, false))
        );
        assert_eq!(made.get(), 3);
        // A failure is not stored.
        assert_eq!(
            cache.get_or_try::<u32, ()>(None, key("r", 1, "b"), || Err(())),
            Err(())
        );
        assert_eq!(
            cache.get_or_try(None, key("r", 1, "b"), || make(4)),
            Ok((4, false))
        );
        // The least recently used go first.
        for i in 0..CAPACITY as u32 {
            cache.get_or_try(None, key("x", i, ""), || make(i)).unwrap();
        }
        assert_eq!(cache.len(), CAPACITY);
        assert_eq!(
            cache.get_or_try(None, key("r", 1, "a"), || make(5)),
            Ok((5, false))
        );
        assert_eq!(
            cache.get_or_try(None, key("x", CAPACITY as u32 - 1, ""), || make(0)),
            Ok((CAPACITY as u32 - 1, true))
        );
    }
}

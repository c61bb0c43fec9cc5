//! Saving and restoring the fluid: every particle's position, velocity, solver stiffness and
//! liquid ([`FluidMaterial`]) in order, the [`SphParams`] (with its liquids) and the sub-step
//! clock, as one JSON document (`serde_json`; the
//! parameters through Bevy's reflection serializer, so a new parameter needs no code here).
//! Restoring into an app with the same plugins reproduces the run bit for bit. See
//! [`SphPlugin`](crate::fluid::SphPlugin) and the format table in `docs/guide.md` ("Save and restore").

use crate::fluid::SphParams;
use crate::fluid::SphSolver;
use crate::fluid::{FluidMaterial, FluidParticle, Position, Stiffness, Velocity};
use crate::sim::clock::SubstepClock;
use bevy::prelude::*;
use bevy::reflect::serde::{TypedReflectDeserializer, TypedReflectSerializer};
use serde::de::DeserializeSeed;
use serde::{Deserialize, Serialize};

/// What the `format` field of a snapshot says.
pub const SNAPSHOT_FORMAT: &str = "bevy_sph2d fluid snapshot";

/// The snapshot layout this version writes and reads.
pub const SNAPSHOT_VERSION: u32 = 1;

/// Why a snapshot could not be written or read. Nothing in the world changes when reading fails.
#[derive(Debug, Clone, PartialEq)]
pub enum SnapshotError {
    /// The file could not be read or written.
    Io(String),
    /// The text is not a snapshot (not JSON, the wrong format, a missing or mistyped field, cut
    /// short).
    Format(String),
    /// A snapshot of another layout version.
    Version(u32),
    /// The parameters in it are not valid.
    Params(String),
    /// Its particle lists do not agree or hold a non-finite value.
    Particles(String),
}

impl core::fmt::Display for SnapshotError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Io(e) => write!(f, "fluid snapshot: {e}"),
            Self::Format(e) => write!(f, "not a fluid snapshot: {e}"),
            Self::Version(v) => write!(
                f,
                "fluid snapshot version {v}; this build reads version {SNAPSHOT_VERSION}"
            ),
            Self::Params(e) => write!(f, "fluid snapshot with invalid parameters: {e}"),
            Self::Particles(e) => write!(f, "fluid snapshot with bad particles: {e}"),
        }
    }
}

impl std::error::Error for SnapshotError {}

/// The clock's state that the next sub-steps depend on.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq)]
struct SavedClock {
    time: f64,
    dt: f32,
    stable_dt: f32,
    max_acceleration: f32,
    total_substeps: u64,
    dropped: f64,
}

/// The document, as written.
#[derive(Serialize, Deserialize, Debug, Clone)]
struct Document {
    format: String,
    version: u32,
    /// [`SphParams`] through Bevy's reflection serializer, as written (f32 values stay short).
    params: Box<serde_json::value::RawValue>,
    clock: SavedClock,
    /// `[x, y]` per particle, m.
    position: Vec<[f32; 2]>,
    /// `[vx, vy]`, m/s.
    velocity: Vec<[f32; 2]>,
    /// `[κ, κᵛ]`, m²/s² (the divergence-free solver's warm start).
    stiffness: Vec<[f32; 2]>,
    /// Each particle's [`FluidMaterial`]; empty (or missing, in a snapshot written before two
    /// liquids) when every particle is the base liquid.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    material: Vec<u8>,
}

/// The fluid's whole state as JSON text: the particles in the order the solver visits them, the
/// parameters and the clock.
pub fn save_fluid(world: &mut World) -> Result<String, SnapshotError> {
    let registry = world.resource::<AppTypeRegistry>().clone();
    let registry = registry.read();
    let params = world.resource::<SphParams>();
    let params = serde_json::to_string(&TypedReflectSerializer::new(params, &registry))
        .and_then(serde_json::value::RawValue::from_string)
        .map_err(|e| SnapshotError::Format(e.to_string()))?;
    let clock = *world.resource::<SphSolver>().clock();
    let mut query = world.query_filtered::<
        (&Position, &Velocity, &Stiffness, Option<&FluidMaterial>),
        With<FluidParticle>,
    >();
    let (mut position, mut velocity, mut stiffness) = (Vec::new(), Vec::new(), Vec::new());
    let mut material = Vec::new();
    for (p, v, k, m) in query.iter(world) {
        position.push(p.0.to_array());
        velocity.push(v.0.to_array());
        stiffness.push(k.0.to_array());
        material.push(m.map_or(0, |m| m.0));
    }
    if material.iter().all(|&m| m == 0) {
        material.clear();
    }
    let document = Document {
        format: SNAPSHOT_FORMAT.into(),
        version: SNAPSHOT_VERSION,
        params,
        clock: SavedClock {
            time: clock.time,
            dt: clock.dt,
            stable_dt: clock.stable_dt,
            max_acceleration: clock.max_acceleration,
            total_substeps: clock.total_substeps,
            dropped: clock.dropped,
        },
        position,
        velocity,
        stiffness,
        material,
    };
    serde_json::to_string(&document).map_err(|e| SnapshotError::Format(e.to_string()))
}

/// Replaces the fluid by the snapshot in `text`: despawns every fluid particle, spawns the saved
/// ones in their order, and sets the parameters and the clock. Checks everything first: on an
/// error the world is as it was. Returns the number of particles.
pub fn load_fluid(world: &mut World, text: &str) -> Result<usize, SnapshotError> {
    let document: Document =
        serde_json::from_str(text).map_err(|e| SnapshotError::Format(e.to_string()))?;
    if document.format != SNAPSHOT_FORMAT {
        return Err(SnapshotError::Format(format!(
            "its format is '{}', not '{SNAPSHOT_FORMAT}'",
            document.format
        )));
    }
    if document.version != SNAPSHOT_VERSION {
        return Err(SnapshotError::Version(document.version));
    }
    let params = {
        let registry = world.resource::<AppTypeRegistry>().clone();
        let registry = registry.read();
        let registration = registry
            .get(core::any::TypeId::of::<SphParams>())
            .ok_or_else(|| SnapshotError::Params("SphParams is not registered".into()))?;
        let mut json = serde_json::Deserializer::from_str(document.params.get());
        let reflected = TypedReflectDeserializer::new(registration, &registry)
            .deserialize(&mut json)
            .map_err(|e| SnapshotError::Params(e.to_string()))?;
        SphParams::from_reflect(reflected.as_partial_reflect())
            .ok_or_else(|| SnapshotError::Params("not an SphParams".into()))?
    };
    params
        .validate()
        .map_err(|e| SnapshotError::Params(e.to_string()))?;
    let n = document.position.len();
    if document.velocity.len() != n || document.stiffness.len() != n {
        return Err(SnapshotError::Particles(format!(
            "{n} positions, {} velocities and {} stiffnesses",
            document.velocity.len(),
            document.stiffness.len()
        )));
    }
    if !(document.material.is_empty() || document.material.len() == n) {
        return Err(SnapshotError::Particles(format!(
            "{n} positions and {} materials",
            document.material.len()
        )));
    }
    let finite = |list: &[[f32; 2]]| list.iter().flatten().all(|v| v.is_finite());
    if !(finite(&document.position) && finite(&document.velocity) && finite(&document.stiffness)) {
        return Err(SnapshotError::Particles("a value is not finite".into()));
    }
    let c = document.clock;
    if !(c.time.is_finite() && c.time >= 0.0 && c.dt.is_finite() && c.dt >= 0.0) {
        return Err(SnapshotError::Format(format!(
            "clock at {} s with step {} s",
            c.time, c.dt
        )));
    }

    let old: Vec<Entity> = world
        .query_filtered::<Entity, With<FluidParticle>>()
        .iter(world)
        .collect();
    for entity in old {
        world.despawn(entity);
    }
    *world.resource_mut::<SphParams>() = params;
    world
        .resource_mut::<SphSolver>()
        .restore_clock(SubstepClock {
            time: c.time,
            dt: c.dt,
            stable_dt: c.stable_dt,
            max_acceleration: c.max_acceleration,
            total_substeps: c.total_substeps,
            dropped: c.dropped,
            ..default()
        });
    let material = |i: usize| FluidMaterial(document.material.get(i).copied().unwrap_or(0));
    world.spawn_batch(
        document
            .position
            .iter()
            .zip(&document.velocity)
            .zip(&document.stiffness)
            .enumerate()
            .map(|(i, ((p, v), k))| {
                (
                    FluidParticle,
                    Position(Vec2::from_array(*p)),
                    Velocity(Vec2::from_array(*v)),
                    Stiffness(Vec2::from_array(*k)),
                    material(i),
                )
            })
            .collect::<Vec<_>>(),
    );
    Ok(n)
}

/// [`save_fluid`] into the file at `path`.
pub fn save_fluid_to(world: &mut World, path: &std::path::Path) -> Result<(), SnapshotError> {
    let text = save_fluid(world)?;
    FileStorage.write(path, &text)
}

/// [`load_fluid`] from the file at `path`.
pub fn load_fluid_from(world: &mut World, path: &std::path::Path) -> Result<usize, SnapshotError> {
    let text = FileStorage.read(path)?;
    load_fluid(world, &text)
}

/// Where a [`SnapshotSlot`] keeps its text, by the slot's path: files by default
/// ([`FileStorage`]). A build without a file system (the web, say) puts its own storage in the
/// slot, the browser's local storage under the path as a key for instance, and the keyboard's
/// and the panel's save and load go there instead:
///
/// ```
/// use bevy_sph2d::gameplay::{SnapshotError, SnapshotSlot, SnapshotStorage};
/// use std::{collections::HashMap, path::Path, sync::Mutex};
///
/// /// Keeps the slots in memory.
/// #[derive(Default)]
/// struct Memory(Mutex<HashMap<String, String>>);
///
/// impl SnapshotStorage for Memory {
///     fn write(&self, path: &Path, text: &str) -> Result<(), SnapshotError> {
///         let key = path.display().to_string();
///         self.0.lock().unwrap().insert(key, text.to_owned());
///         Ok(())
///     }
///     fn read(&self, path: &Path) -> Result<String, SnapshotError> {
///         let key = path.display().to_string();
///         let slots = self.0.lock().unwrap();
///         slots.get(&key).cloned().ok_or(SnapshotError::Io(format!("{key}: empty")))
///     }
/// }
///
/// let slot = SnapshotSlot::default().with_storage(Memory::default());
/// # let _ = slot;
/// ```
pub trait SnapshotStorage: Send + Sync + 'static {
    /// Stores `text` under `path`.
    fn write(&self, path: &std::path::Path, text: &str) -> Result<(), SnapshotError>;
    /// The text stored under `path`.
    fn read(&self, path: &std::path::Path) -> Result<String, SnapshotError>;
}

/// [`SnapshotStorage`] in files (`std::fs`), the path relative to the working directory.
#[derive(Debug, Clone, Copy, Default)]
pub struct FileStorage;

impl SnapshotStorage for FileStorage {
    fn write(&self, path: &std::path::Path, text: &str) -> Result<(), SnapshotError> {
        std::fs::write(path, text)
            .map_err(|e| SnapshotError::Io(format!("{}: {e}", path.display())))
    }

    fn read(&self, path: &std::path::Path) -> Result<String, SnapshotError> {
        std::fs::read_to_string(path)
            .map_err(|e| SnapshotError::Io(format!("{}: {e}", path.display())))
    }
}

/// Where the keyboard's and the panel's save and load go (`F5` saves, `F9` loads), and how the
/// last one went.
#[derive(Resource, Clone)]
pub struct SnapshotSlot {
    /// The slot's file (its key in a storage that has no files).
    pub path: std::path::PathBuf,
    /// What the last save or load did, for the panel.
    pub status: Option<Result<String, String>>,
    /// Where the text goes: files unless [`with_storage`](Self::with_storage) says otherwise.
    pub storage: std::sync::Arc<dyn SnapshotStorage>,
}

impl SnapshotSlot {
    /// The slot with its text kept in `storage` instead of files.
    pub fn with_storage(mut self, storage: impl SnapshotStorage) -> Self {
        self.storage = std::sync::Arc::new(storage);
        self
    }
}

impl std::fmt::Debug for SnapshotSlot {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SnapshotSlot")
            .field("path", &self.path)
            .field("status", &self.status)
            .finish_non_exhaustive()
    }
}

impl Default for SnapshotSlot {
    fn default() -> Self {
        Self {
            path: "bevy_sph2d_slot.json".into(),
            status: None,
            storage: std::sync::Arc::new(FileStorage),
        }
    }
}

/// Runs `action` on the [`SnapshotSlot`]'s path and storage and records how it went (warning
/// on failure).
fn with_slot(
    world: &mut World,
    action: impl FnOnce(
        &mut World,
        &std::path::Path,
        &dyn SnapshotStorage,
    ) -> Result<String, SnapshotError>,
) {
    let slot = world.get_resource_or_init::<SnapshotSlot>();
    let (path, storage) = (slot.path.clone(), slot.storage.clone());
    let status = action(world, &path, storage.as_ref()).map_err(|error| {
        warn!("{error}");
        error.to_string()
    });
    world.resource_mut::<SnapshotSlot>().status = Some(status);
}

/// A command that saves the fluid into the [`SnapshotSlot`].
#[derive(Debug, Clone, Copy, Default)]
pub struct SaveSlot;

impl Command for SaveSlot {
    type Out = ();

    fn apply(self, world: &mut World) {
        with_slot(world, |world, path, storage| {
            let text = save_fluid(world)?;
            storage.write(path, &text)?;
            Ok(format!("saved to {}", path.display()))
        });
    }
}

/// A command that loads the fluid from the [`SnapshotSlot`] (nothing changes if it cannot).
#[derive(Debug, Clone, Copy, Default)]
pub struct LoadSlot;

impl Command for LoadSlot {
    type Out = ();

    fn apply(self, world: &mut World) {
        with_slot(world, |world, path, storage| {
            let n = load_fluid(world, &storage.read(path)?)?;
            Ok(format!("loaded {n} particles from {}", path.display()))
        });
    }
}

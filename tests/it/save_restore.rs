//! Save and restore: a run continued from a snapshot in a fresh app matches the original bit
//! for bit, for both solvers; text that is not a snapshot, a cut-short one and one of another
//! version are refused with a clear error and change nothing.

use crate::common::{create_app, run, spawn, states};
use bevy::prelude::*;
use bevy_sph2d::fluid::{FluidMaterial, FluidParticle, Liquid, Position, SphParams, Tank};
use bevy_sph2d::gameplay::{FluidBlock, SnapshotError, load_fluid, save_fluid};

fn params(base: SphParams) -> SphParams {
    SphParams {
        particle_spacing: 0.01,
        tank: Some(Tank::new(0.6, 0.4)),
        ..base
    }
}

fn count(app: &mut App) -> usize {
    app.world_mut()
        .query_filtered::<(), With<FluidParticle>>()
        .iter(app.world())
        .count()
}

/// Makes the particles right of `x` (m) the first of the params' liquids.
fn second_liquid_right_of(app: &mut App, x: f32) {
    let world = app.world_mut();
    let right: Vec<Entity> = world
        .query_filtered::<(Entity, &Position), With<FluidParticle>>()
        .iter(world)
        .filter(|(_, p)| p.0.x > x)
        .map(|(e, _)| e)
        .collect();
    for entity in right {
        world.entity_mut(entity).insert(FluidMaterial(1));
    }
}

/// How many particles are of the second liquid.
fn second_liquid(app: &mut App) -> usize {
    let world = app.world_mut();
    world
        .query::<&FluidMaterial>()
        .iter(world)
        .filter(|m| m.0 == 1)
        .count()
}

fn round_trip(base: SphParams) {
    let two_liquids = !base.liquids.is_empty();
    let mut original = create_app(params(base.clone()));
    spawn(&mut original, FluidBlock::dam_break(0.15, 0.3).with_seed(4));
    if two_liquids {
        second_liquid_right_of(&mut original, 0.075);
    }
    run(&mut original, 30);
    let text = save_fluid(original.world_mut()).expect("saved");
    run(&mut original, 30);
    let expected = states(&mut original);

    // A fresh app on other parameters: the snapshot brings its own.
    let mut restored = create_app(SphParams::default());
    restored.update();
    let loaded = load_fluid(restored.world_mut(), &text).expect("loaded");
    assert_eq!(loaded, expected.len());
    assert_eq!(*restored.world().resource::<SphParams>(), params(base));
    assert_eq!(second_liquid(&mut restored), second_liquid(&mut original));
    assert_eq!(second_liquid(&mut restored) > 0, two_liquids);
    run(&mut restored, 30);
    let got = states(&mut restored);
    assert_eq!(got.len(), expected.len());
    for (a, b) in expected.iter().zip(&got) {
        assert_eq!(
            a.position.to_array().map(f32::to_bits),
            b.position.to_array().map(f32::to_bits)
        );
        assert_eq!(
            a.velocity.to_array().map(f32::to_bits),
            b.velocity.to_array().map(f32::to_bits)
        );
    }
}

#[test]
fn a_restored_run_matches_the_original_bit_for_bit() {
    round_trip(SphParams::water());
}

/// Brine in the column's right half: the snapshot keeps each particle's liquid and the liquids
/// of the parameters, and the restored run is the same bits.
#[test]
fn a_restored_run_of_two_liquids_matches_the_original_bit_for_bit() {
    round_trip(SphParams {
        liquids: vec![Liquid::brine()],
        ..SphParams::water()
    });
}

#[test]
fn a_restored_run_matches_the_original_bit_for_bit_wcsph() {
    round_trip(SphParams::water_wcsph());
}

#[test]
fn bad_snapshots_are_refused_and_change_nothing() {
    let mut app = create_app(params(SphParams::water()));
    spawn(&mut app, FluidBlock::dam_break(0.1, 0.1));
    let before = count(&mut app);
    let text = save_fluid(app.world_mut()).unwrap();
    let other_version = text.replacen("\"version\":1", "\"version\":7", 1);
    let bad_params = text.replacen("\"particle_spacing\":0.01", "\"particle_spacing\":-1.0", 1);
    let uneven = {
        let mut document: serde_json::Value = serde_json::from_str(&text).unwrap();
        document["velocity"].as_array_mut().unwrap().pop();
        document.to_string()
    };
    for (name, bad) in [
        ("not JSON", "hello".to_string()),
        ("another document", "{\"format\":\"png\"}".to_string()),
        ("cut short", text[..text.len() / 2].to_string()),
        ("another version", other_version),
        ("invalid parameters", bad_params),
        ("broken particle list", uneven),
    ] {
        let error = load_fluid(app.world_mut(), &bad).expect_err(name);
        println!("{name}: {error}");
        match (name, &error) {
            ("another version", SnapshotError::Version(7)) => {}
            ("invalid parameters", SnapshotError::Params(message)) => {
                assert!(message.contains("particle_spacing"), "{message}")
            }
            ("broken particle list", SnapshotError::Particles(_)) => {}
            ("another version" | "invalid parameters" | "broken particle list", _) => {
                panic!("{name}: {error}")
            }
            _ => {}
        }
        assert_eq!(count(&mut app), before, "{name}");
    }
    assert_eq!(app.world().resource::<SphParams>().particle_spacing, 0.01);
}

/// Queues a save or load `command` and applies it at once.
fn slot_command(app: &mut App, command: impl Command) {
    app.world_mut().commands().queue(command);
    app.world_mut().flush();
}

/// The slot's last load succeeded.
fn assert_slot_loaded(app: &App) {
    let slot = app.world().resource::<bevy_sph2d::gameplay::SnapshotSlot>();
    assert!(
        matches!(&slot.status, Some(Ok(m)) if m.contains("loaded")),
        "{:?}",
        slot.status
    );
}

#[test]
fn the_slot_commands_save_and_load_a_file() {
    let mut app = create_app(params(SphParams::water()));
    spawn(&mut app, FluidBlock::dam_break(0.1, 0.1));
    let path = std::env::temp_dir().join(format!("bevy_sph2d_slot_{}.json", std::process::id()));
    app.world_mut()
        .resource_mut::<bevy_sph2d::gameplay::SnapshotSlot>()
        .path = path.clone();
    let before = states(&mut app);
    slot_command(&mut app, bevy_sph2d::gameplay::SaveSlot);
    run(&mut app, 20);
    slot_command(&mut app, bevy_sph2d::gameplay::LoadSlot);
    assert_slot_loaded(&app);
    let after = states(&mut app);
    assert_eq!(
        before.iter().map(|s| s.position).collect::<Vec<_>>(),
        after.iter().map(|s| s.position).collect::<Vec<_>>()
    );
    let _ = std::fs::remove_file(&path);
    // A missing file: refused, nothing lost.
    slot_command(&mut app, bevy_sph2d::gameplay::LoadSlot);
    let slot = app.world().resource::<bevy_sph2d::gameplay::SnapshotSlot>();
    assert!(matches!(&slot.status, Some(Err(_))), "{:?}", slot.status);
    assert_eq!(states(&mut app).len(), before.len());
}

/// Keeps the slot's text in memory, as a build without a file system would.
#[derive(Default, Clone)]
struct Memory(std::sync::Arc<std::sync::Mutex<Option<String>>>);

impl bevy_sph2d::gameplay::SnapshotStorage for Memory {
    fn write(
        &self,
        _: &std::path::Path,
        text: &str,
    ) -> Result<(), bevy_sph2d::gameplay::SnapshotError> {
        *self.0.lock().unwrap() = Some(text.to_owned());
        Ok(())
    }

    fn read(&self, path: &std::path::Path) -> Result<String, bevy_sph2d::gameplay::SnapshotError> {
        self.0.lock().unwrap().clone().ok_or_else(|| {
            bevy_sph2d::gameplay::SnapshotError::Io(format!("{}: empty", path.display()))
        })
    }
}

#[test]
fn the_slot_commands_go_through_the_slots_storage() {
    let mut app = create_app(params(SphParams::water()));
    spawn(&mut app, FluidBlock::dam_break(0.1, 0.1));
    let memory = Memory::default();
    let path = std::path::PathBuf::from("no/such/folder/slot.json");
    app.world_mut().insert_resource(
        bevy_sph2d::gameplay::SnapshotSlot {
            path: path.clone(),
            ..default()
        }
        .with_storage(memory.clone()),
    );
    let before = states(&mut app);
    slot_command(&mut app, bevy_sph2d::gameplay::SaveSlot);
    assert!(memory.0.lock().unwrap().is_some(), "nothing was stored");
    assert!(!path.exists());
    run(&mut app, 20);
    slot_command(&mut app, bevy_sph2d::gameplay::LoadSlot);
    assert_slot_loaded(&app);
    assert_eq!(
        before.iter().map(|s| s.position).collect::<Vec<_>>(),
        states(&mut app)
            .iter()
            .map(|s| s.position)
            .collect::<Vec<_>>()
    );
}

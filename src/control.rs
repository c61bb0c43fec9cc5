//! Pause, single-step and reset, shared by every simulation plugin of the crate. See
//! [`SimulationControlPlugin`].

use bevy::ecs::intern::Interned;
use bevy::ecs::schedule::ScheduleLabel;
use bevy::prelude::*;

/// Whether the simulations step this tick: pause, resume or single-step them from a game, a key
/// binding or the panel.
///
/// The simulation plugins run their sets only in ticks where [`is_running`](Self::is_running)
/// says so (see [`simulation_running`]).
#[derive(Resource, Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct SimulationControl {
    /// Stops the simulations (rendering and input go on).
    pub paused: bool,
    /// Ticks still to run while paused (each [`step`](Self::step) adds one).
    pub pending_steps: u32,
    running: bool,
}

impl SimulationControl {
    /// Pauses a running simulation, or resumes a paused one.
    pub fn toggle_pause(&mut self) {
        self.paused = !self.paused;
    }

    /// Runs one more fixed tick, then stays paused (pauses first if running).
    pub fn step(&mut self) {
        self.paused = true;
        self.pending_steps = self.pending_steps.saturating_add(1);
    }

    /// Whether the simulations step in the current tick.
    pub fn is_running(&self) -> bool {
        self.running
    }

    fn begin_tick(&mut self) {
        self.running = if !self.paused {
            true
        } else if self.pending_steps > 0 {
            self.pending_steps -= 1;
            true
        } else {
            false
        };
    }
}

/// Asks the simulations to start again from their scenario (the fluid respawns its
/// [`SphScenario`](crate::gameplay::SphScenario)).
#[derive(Message, Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ResetSimulation;

/// The decision whether this tick steps, made once per tick before every simulation set.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct SimulationControlSystems;

/// Run condition: the simulations step this tick (true when there is no
/// [`SimulationControl`]).
pub fn simulation_running(control: Option<Res<SimulationControl>>) -> bool {
    control.is_none_or(|control| control.is_running())
}

/// Adds [`SimulationControl`] and [`ResetSimulation`];
/// [`ParticleSchedulePlugin`](crate::schedule::ParticleSchedulePlugin) adds it (once) in the
/// particle schedule, so a game rarely needs to.
pub struct SimulationControlPlugin {
    /// The fixed schedule the simulations step in.
    pub schedule: Interned<dyn ScheduleLabel>,
}

impl Default for SimulationControlPlugin {
    fn default() -> Self {
        Self {
            schedule: FixedUpdate.intern(),
        }
    }
}

impl Plugin for SimulationControlPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<SimulationControl>()
            .init_resource::<SimulationControl>()
            .add_message::<ResetSimulation>()
            .add_systems(
                self.schedule,
                begin_control_tick.in_set(SimulationControlSystems),
            );
    }
}

fn begin_control_tick(mut control: ResMut<SimulationControl>) {
    control.begin_tick();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_steps_run_one_tick_each() {
        let mut control = SimulationControl::default();
        control.begin_tick();
        assert!(control.is_running());
        control.step();
        control.step();
        let ran: Vec<bool> = (0..4)
            .map(|_| {
                control.begin_tick();
                control.is_running()
            })
            .collect();
        assert_eq!(ran, [true, true, false, false]);
        control.toggle_pause();
        control.begin_tick();
        assert!(control.is_running());
    }
}

//! The sub-stepping policy, written once: how a fixed tick is split into stable sub-steps, and
//! the simulated time so far. Pure data; the ECS systems and the slice solver both drive one
//! [`SubstepClock`] the same way:
//!
//! ```text
//! clock.begin_tick(tick);
//! while clock.wants_substep(max_substeps) {
//!     // ... forces, then the stability limit `stable` ...
//!     let dt = clock.take_substep(stable, max_substeps, particles == 0);
//!     // ... integrate by dt ...
//! }
//! clock.end_tick();
//! ```
//!

/// The fraction of a tick below which what is left of it counts as done.
const END_OF_TICK: f64 = 1e-6;

/// How the current tick is being split into sub-steps, and the simulated time so far.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubstepClock {
    /// Length of the current tick, s.
    pub tick: f64,
    /// What is left of it, s.
    pub remaining: f64,
    /// Sub-steps taken in the current tick.
    pub substeps: u32,
    /// The sub-step being integrated (or last integrated), s.
    pub dt: f32,
    /// The stability limit at the last sub-step, s.
    pub stable_dt: f32,
    /// Largest acceleration at the last sub-step, m/s².
    pub max_acceleration: f32,
    /// Simulated time, s.
    pub time: f64,
    /// Sub-steps taken since start-up.
    pub total_substeps: u64,
    /// Simulated time dropped because ticks needed more than `max_substeps`, s.
    pub dropped: f64,
}

impl SubstepClock {
    /// Starts a tick of `tick` seconds.
    pub fn begin_tick(&mut self, tick: f64) {
        self.tick = tick;
        self.remaining = tick;
        self.substeps = 0;
    }

    /// Whether the tick needs another sub-step and `max_substeps` allows one. What rounding
    /// leaves of a tick split into `f32` steps (a millionth of it) is not worth a step: an
    /// implicit solver asked to remove a density error within a sliver of time would answer
    /// with an enormous pressure.
    pub fn wants_substep(&self, max_substeps: u32) -> bool {
        self.remaining > END_OF_TICK * self.tick && self.substeps < max_substeps
    }

    /// Takes the next sub-step given the stability limit `stable` (s) and returns its length:
    /// what is left of the tick split into equal steps no longer than `stable`; on the last
    /// allowed sub-step just `stable` (the rest of the tick is dropped at
    /// [`end_tick`](Self::end_tick)); with no particles, the whole rest of the tick.
    pub fn take_substep(&mut self, stable: f32, max_substeps: u32, empty: bool) -> f32 {
        let dt = if empty {
            self.remaining as f32
        } else if self.substeps + 1 >= max_substeps {
            stable.min(self.remaining as f32)
        } else {
            plan_substep(self.remaining, stable)
        };
        self.record(dt, stable);
        self.remaining -= dt as f64;
        self.substeps += 1;
        dt
    }

    /// Takes one sub-step of exactly `stable` seconds outside any tick (benchmarks, tests).
    pub fn take_free_substep(&mut self, stable: f32) -> f32 {
        self.record(stable, stable);
        stable
    }

    /// Ends the tick; time it could not cover counts as dropped.
    pub fn end_tick(&mut self) {
        if self.remaining > END_OF_TICK * self.tick {
            self.dropped += self.remaining;
        }
        self.remaining = 0.0;
    }

    fn record(&mut self, dt: f32, stable: f32) {
        self.dt = dt;
        self.stable_dt = stable;
        self.time += dt as f64;
        self.total_substeps += 1;
    }
}

/// Splits what is left of a tick into equal sub-steps no longer than `stable` and returns the
/// next one (s).
pub fn plan_substep(remaining: f64, stable: f32) -> f32 {
    if remaining <= 0.0 {
        return 0.0;
    }
    let stable = (stable as f64).max(1e-9);
    let count = (remaining / stable).ceil().max(1.0);
    (remaining / count) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tick_splits_into_equal_stable_substeps() {
        let mut clock = SubstepClock::default();
        clock.begin_tick(0.01);
        let mut steps = Vec::new();
        while clock.wants_substep(100) {
            steps.push(clock.take_substep(0.003, 100, false));
        }
        clock.end_tick();
        assert_eq!(steps.len(), 4);
        assert!(steps.iter().all(|&dt| (dt - 0.0025).abs() < 1e-7));
        assert!((clock.time - 0.01).abs() < 1e-9);
        assert_eq!(clock.dropped, 0.0);
    }

    #[test]
    fn the_step_budget_drops_time_instead_of_growing_the_step() {
        let mut clock = SubstepClock::default();
        clock.begin_tick(0.01);
        while clock.wants_substep(2) {
            clock.take_substep(0.001, 2, false);
        }
        clock.end_tick();
        assert_eq!(clock.substeps, 2);
        assert!((clock.time - 0.002).abs() < 1e-9);
        assert!((clock.dropped - 0.008).abs() < 1e-9);
    }
}

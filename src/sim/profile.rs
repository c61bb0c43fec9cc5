//! Where a sub-step's time goes: a [`StageProfile`] the stages of [`step`](super::step) add
//! their wall time to while a driver has switched it on (the `bench` example's `--breakdown`).
//! The core keeps no clock of its own (it also runs where `std::time` has none, the web): the
//! driver that switches the profile on gives it one. Switched off (the default) it costs one
//! branch per part of a sub-step.

/// The parts of a sub-step a [`StageProfile`] times, in the order they run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SubstepPart {
    /// The walls placed, the cell grid and the sorted snapshot (the neighbours stage).
    Neighbors,
    /// Densities, neighbour caches and solver factors (WCSPH: density and pressure).
    Density,
    /// The divergence-free solve (DFSPH).
    DivergenceSolve,
    /// The non-pressure forces (WCSPH: every force) and their copy into the particles.
    Forces,
    /// The start of the density solve (DFSPH): the velocities predicted under every
    /// acceleration.
    PressureStart,
    /// With the grid start (DFSPH), the pressure on the coarse grid: the particles spread onto
    /// it, its solve, and its pressure read back at the particles as the density solve's start.
    GridPressure,
    /// The density solve under every acceleration (DFSPH).
    DensitySolve,
    /// The step length, the move of every particle and the solids' impulses.
    Integrate,
}

impl SubstepPart {
    /// Every part, in the order of a sub-step.
    pub const ALL: [SubstepPart; 8] = [
        Self::Neighbors,
        Self::Density,
        Self::DivergenceSolve,
        Self::Forces,
        Self::PressureStart,
        Self::GridPressure,
        Self::DensitySolve,
        Self::Integrate,
    ];

    /// A short name, for reports.
    pub fn label(self) -> &'static str {
        match self {
            Self::Neighbors => "neighbours",
            Self::Density => "density",
            Self::DivergenceSolve => "divergence_solve",
            Self::Forces => "forces",
            Self::PressureStart => "pressure_start",
            Self::GridPressure => "grid_pressure",
            Self::DensitySolve => "density_solve",
            Self::Integrate => "integrate",
        }
    }
}

/// Wall time of each [`SubstepPart`] of the sub-steps run since the profile was switched on.
#[derive(Debug, Clone, Copy)]
pub struct StageProfile {
    /// The driver's clock: seconds since any fixed moment.
    now: fn() -> f64,
    seconds: [f64; SubstepPart::ALL.len()],
    substeps: u64,
}

impl StageProfile {
    /// An empty profile timed by `now` (seconds since any fixed moment).
    pub fn new(now: fn() -> f64) -> Self {
        Self {
            now,
            seconds: [0.0; SubstepPart::ALL.len()],
            substeps: 0,
        }
    }

    /// The clock's reading, s.
    pub(crate) fn now(&self) -> f64 {
        (self.now)()
    }

    /// Adds the time since `started` (a reading of [`now`](Self::now)) to `part`.
    pub(crate) fn add(&mut self, part: SubstepPart, started: f64) {
        self.seconds[part as usize] += (self.now)() - started;
    }

    /// Counts one sub-step.
    pub(crate) fn count_substep(&mut self) {
        self.substeps += 1;
    }

    /// Seconds spent in `part`.
    pub fn seconds(&self, part: SubstepPart) -> f64 {
        self.seconds[part as usize]
    }

    /// Seconds spent in every part together.
    pub fn total_seconds(&self) -> f64 {
        self.seconds.iter().sum()
    }

    /// Sub-steps timed.
    pub fn substeps(&self) -> u64 {
        self.substeps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ticking() -> f64 {
        use core::sync::atomic::{AtomicU64, Ordering};
        static TICKS: AtomicU64 = AtomicU64::new(0);
        TICKS.fetch_add(1, Ordering::Relaxed) as f64
    }

    #[test]
    fn parts_add_what_the_clock_says() {
        let mut profile = StageProfile::new(ticking);
        let started = profile.now();
        profile.add(SubstepPart::Forces, started);
        let started = profile.now();
        profile.add(SubstepPart::Forces, started);
        profile.count_substep();
        assert_eq!(profile.seconds(SubstepPart::Forces), 2.0);
        assert_eq!(profile.seconds(SubstepPart::Neighbors), 0.0);
        assert_eq!(profile.total_seconds(), 2.0);
        assert_eq!(profile.substeps(), 1);
    }
}

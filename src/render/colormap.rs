//! Pure colour mapping: scalar fields to colours through perceptual colour maps (the `colorous`
//! crate), and the percentile range that auto-scaling uses. See
//! [`ParticleRenderPlugin`](crate::render::ParticleRenderPlugin).

use bevy::color::{Color, LinearRgba, Srgba};
use bevy::reflect::Reflect;

/// A colour map from `colorous` (sequential maps, low values first).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum ColorMap {
    /// White to deep blue: water-like.
    #[default]
    Blues,
    /// Blue-green to yellow (matplotlib's default); perceptually uniform.
    Viridis,
    /// Google's improved rainbow: high contrast, for spotting small differences.
    Turbo,
    /// Blue to yellow through magenta.
    Plasma,
    /// Black to pale yellow through red.
    Inferno,
    /// Blue to yellow, readable with colour-vision deficiency.
    Cividis,
    /// Yellow to blue through green.
    YellowGreenBlue,
}

impl ColorMap {
    /// Every map, in menu order.
    pub const ALL: [ColorMap; 7] = [
        ColorMap::Blues,
        ColorMap::Viridis,
        ColorMap::Turbo,
        ColorMap::Plasma,
        ColorMap::Inferno,
        ColorMap::Cividis,
        ColorMap::YellowGreenBlue,
    ];

    /// The map's name.
    pub fn label(self) -> &'static str {
        match self {
            ColorMap::Blues => "Blues",
            ColorMap::Viridis => "Viridis",
            ColorMap::Turbo => "Turbo",
            ColorMap::Plasma => "Plasma",
            ColorMap::Inferno => "Inferno",
            ColorMap::Cividis => "Cividis",
            ColorMap::YellowGreenBlue => "Yellow-green-blue",
        }
    }

    fn gradient(self) -> colorous::Gradient {
        match self {
            ColorMap::Blues => colorous::BLUES,
            ColorMap::Viridis => colorous::VIRIDIS,
            ColorMap::Turbo => colorous::TURBO,
            ColorMap::Plasma => colorous::PLASMA,
            ColorMap::Inferno => colorous::INFERNO,
            ColorMap::Cividis => colorous::CIVIDIS,
            ColorMap::YellowGreenBlue => colorous::YELLOW_GREEN_BLUE,
        }
    }

    /// The colour at `t` in 0..=1 (clamped; NaN gives the low end).
    pub fn sample(self, t: f32) -> Color {
        let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
        let c = self.gradient().eval_continuous(t as f64);
        Color::Srgba(Srgba::rgb_u8(c.r, c.g, c.b))
    }

    /// A table of `len` (at least 2) evenly spaced colours, low end first, for mapping many
    /// values quickly.
    pub fn table(self, len: usize) -> ColorTable {
        self.table_between(0.0, 1.0, len)
    }

    /// A table of `len` colours evenly spaced over the part `low..=high` of the map (e.g. to
    /// skip a map's near-black end on a dark background).
    pub fn table_between(self, low: f32, high: f32, len: usize) -> ColorTable {
        let len = len.max(2);
        ColorTable {
            colors: (0..len)
                .map(|i| {
                    let t = i as f32 / (len - 1) as f32;
                    self.sample(low + (high - low) * t).to_linear()
                })
                .collect(),
        }
    }
}

/// Evenly spaced samples of a [`ColorMap`], looked up by a value and a range.
#[derive(Debug, Clone, PartialEq)]
pub struct ColorTable {
    colors: Vec<LinearRgba>,
}

impl ColorTable {
    /// The colour of `value` in `range` (values outside it take the end colours; an empty or
    /// reversed range maps everything to the middle).
    pub fn map(&self, value: f32, range: ColorRange) -> LinearRgba {
        let t = range.normalize(value);
        let last = self.colors.len() - 1;
        self.colors[((t * last as f32).round() as usize).min(last)]
    }
}

/// A closed range of values, in the unit of the quantity shown.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
pub struct ColorRange {
    /// The value shown with the map's low end.
    pub min: f32,
    /// The value shown with the map's high end.
    pub max: f32,
}

impl ColorRange {
    /// The range `min..=max`.
    pub fn new(min: f32, max: f32) -> Self {
        Self { min, max }
    }

    /// Where `value` lies in the range, clamped to 0..=1 (0.5 for an empty or invalid range;
    /// 0 for NaN).
    pub fn normalize(self, value: f32) -> f32 {
        let width = self.max - self.min;
        if !(width > 0.0 && width.is_finite()) {
            return 0.5;
        }
        let t = (value - self.min) / width;
        if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) }
    }

    /// The range between the `low` and `high` quantiles (0..=1) of the finite `values`, or
    /// `None` if there are none. Sorts a copy of a sample of at most 4096 values, so it is cheap
    /// for any particle count and ignores a few outliers (splashes, empty kernels).
    pub fn from_quantiles(values: &[f32], low: f32, high: f32) -> Option<Self> {
        let stride = values.len().div_ceil(4096).max(1);
        let mut sample: Vec<f32> = values
            .iter()
            .step_by(stride)
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if sample.is_empty() {
            return None;
        }
        sample.sort_unstable_by(f32::total_cmp);
        let at = |q: f32| {
            let index = (q.clamp(0.0, 1.0) * (sample.len() - 1) as f32).round() as usize;
            sample[index]
        };
        Some(Self::new(at(low.min(high)), at(high.max(low))))
    }

    /// Moves this range a fraction `rate` (0..=1) of the way towards `target`, so an
    /// auto-scaled legend does not flicker from frame to frame.
    pub fn approach(self, target: Self, rate: f32) -> Self {
        let rate = rate.clamp(0.0, 1.0);
        Self::new(
            self.min + (target.min - self.min) * rate,
            self.max + (target.max - self.max) * rate,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_run_from_their_low_to_their_high_end() {
        // Viridis starts dark purple (#440154) and ends yellow (#fde725).
        let low = ColorMap::Viridis.sample(0.0).to_srgba();
        let high = ColorMap::Viridis.sample(1.0).to_srgba();
        assert_eq!(low, Srgba::rgb_u8(0x44, 0x01, 0x54));
        assert_eq!(high, Srgba::rgb_u8(0xfd, 0xe7, 0x25));
        // Blues darkens with the value.
        let lum = |t| {
            let c = ColorMap::Blues.sample(t).to_linear();
            0.2126 * c.red + 0.7152 * c.green + 0.0722 * c.blue
        };
        assert!(lum(0.0) > lum(0.5) && lum(0.5) > lum(1.0));
        // Out of range and NaN clamp to the ends.
        assert_eq!(ColorMap::Turbo.sample(-3.0), ColorMap::Turbo.sample(0.0));
        assert_eq!(ColorMap::Turbo.sample(7.0), ColorMap::Turbo.sample(1.0));
        assert_eq!(
            ColorMap::Turbo.sample(f32::NAN),
            ColorMap::Turbo.sample(0.0)
        );
    }

    #[test]
    fn table_lookup_follows_the_range() {
        let table = ColorMap::Viridis.table(256);
        let range = ColorRange::new(990.0, 1010.0);
        assert_eq!(
            table.map(990.0, range),
            ColorMap::Viridis.sample(0.0).to_linear()
        );
        assert_eq!(
            table.map(2000.0, range),
            ColorMap::Viridis.sample(1.0).to_linear()
        );
        assert_eq!(table.map(f32::NAN, range), table.map(0.0, range));
        let middle = table.map(1000.0, range);
        assert!((middle.green - ColorMap::Viridis.sample(0.5).to_linear().green).abs() < 0.01);
        // A degenerate range shows the middle colour instead of dividing by zero.
        assert_eq!(
            table.map(5.0, ColorRange::new(1.0, 1.0)),
            table.map(0.5, ColorRange::new(0.0, 1.0))
        );
    }

    #[test]
    fn quantiles_ignore_outliers_and_non_finite_values() {
        let mut values: Vec<f32> = (0..1000).map(|i| 1000.0 + i as f32 * 0.01).collect();
        values.push(f32::NAN);
        values.push(1.0e9);
        values.push(-5.0);
        let range = ColorRange::from_quantiles(&values, 0.02, 0.98).unwrap();
        assert!((range.min - 1000.2).abs() < 0.05, "{range:?}");
        assert!((range.max - 1009.8).abs() < 0.05, "{range:?}");
        assert_eq!(ColorRange::from_quantiles(&[f32::NAN], 0.0, 1.0), None);
        let eased = ColorRange::new(0.0, 10.0).approach(ColorRange::new(10.0, 20.0), 0.25);
        assert_eq!(eased, ColorRange::new(2.5, 12.5));
    }
}

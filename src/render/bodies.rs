//! Sprites for gravity bodies that are not fluid particles, tinted by speed or mass. See
//! [`ParticleRenderPlugin`](crate::render::ParticleRenderPlugin).

use super::{ColorMap, ColorRange, ColorTable, ParticleTexture, PreviousPosition};
use crate::fluid::FluidParticle;
use crate::gravity::Mass;
use crate::particle::{Position, Velocity};
use bevy::prelude::*;

/// What body sprites show.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum BodyColor {
    /// Speed, m/s.
    #[default]
    Speed,
    /// Mass, kg.
    Mass,
}

/// How gravity bodies are drawn.
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct BodyView {
    /// Sprite diameter, m (the heaviest bodies are drawn up to four times larger).
    pub size: f32,
    /// The quantity the colour shows.
    pub color_by: BodyColor,
    /// The colour map (its darkest fifth is skipped, so slow or light bodies stay visible on a
    /// dark background).
    pub color_map: ColorMap,
    /// Follow the data: [`range`](Self::range) is updated every frame.
    pub auto_range: bool,
    /// The values at the map's ends.
    pub range: ColorRange,
}

impl Default for BodyView {
    fn default() -> Self {
        Self {
            size: 0.01,
            color_by: BodyColor::Speed,
            color_map: ColorMap::Plasma,
            auto_range: true,
            range: ColorRange::new(0.0, 1.0),
        }
    }
}

/// Gives a new body that is not a fluid particle its sprite.
pub(super) fn attach_body_sprite(
    add: On<Add, Mass>,
    bodies: Query<(&Position, Has<FluidParticle>)>,
    texture: Option<Res<ParticleTexture>>,
    view: Res<BodyView>,
    mut commands: Commands,
) {
    let Ok((position, fluid)) = bodies.get(add.entity) else {
        return;
    };
    if fluid {
        return;
    }
    commands.entity(add.entity).insert((
        Sprite {
            image: texture.map(|t| t.0.clone()).unwrap_or_default(),
            custom_size: Some(Vec2::splat(view.size)),
            ..default()
        },
        Transform::from_translation(position.extend(0.5)),
        PreviousPosition(position.0),
    ));
}

fn shown(color_by: BodyColor, velocity: &Velocity, mass: &Mass) -> f32 {
    match color_by {
        BodyColor::Speed => velocity.length(),
        BodyColor::Mass => mass.0,
    }
}

/// What the body sprite pass reads and writes.
type BodySprite = (
    &'static Position,
    &'static PreviousPosition,
    &'static Velocity,
    &'static Mass,
    &'static mut Transform,
    &'static mut Sprite,
);

/// Auto-ranges, then moves and tints body sprites in parallel.
pub(super) fn update_body_sprites(
    mut view: ResMut<BodyView>,
    fixed: Res<Time<Fixed>>,
    mut values: Local<Vec<f32>>,
    mut table: Local<Option<(ColorMap, ColorTable)>>,
    mut bodies: Query<BodySprite, Without<FluidParticle>>,
) {
    if bodies.is_empty() {
        return;
    }
    let color_by = view.color_by;
    let stride = bodies.iter().len().div_ceil(super::QUANTILE_SAMPLE).max(1);
    values.clear();
    values.extend(
        bodies
            .iter()
            .step_by(stride)
            .map(|(_, _, v, m, _, _)| shown(color_by, v, m)),
    );
    let heaviest = bodies.iter().map(|b| b.3.0).fold(0.0f32, f32::max);
    if view.auto_range
        && let Some(target) = ColorRange::from_quantiles(&values, 0.01, 0.99)
    {
        let range = view.range.approach(target, 0.1);
        if range != view.range {
            view.range = range;
        }
    }
    if table.as_ref().is_none_or(|(map, _)| *map != view.color_map) {
        *table = Some((view.color_map, view.color_map.table_between(0.2, 1.0, 256)));
    }
    let Some((_, table)) = table.as_ref() else {
        return;
    };
    let alpha = fixed.overstep_fraction().clamp(0.0, 1.0);
    let view = &*view;
    bodies.par_iter_mut().for_each(
        |(position, previous, velocity, mass, mut transform, mut sprite)| {
            let at = previous.0.lerp(position.0, alpha).extend(0.5);
            if transform.translation != at {
                transform.translation = at;
            }
            let color = Color::LinearRgba(table.map(shown(color_by, velocity, mass), view.range));
            // Heavy bodies (a galaxy's centre) stand out: up to 4x for the heaviest.
            let scale = if heaviest > 0.0 {
                (1.0 + 3.0 * (mass.0 / heaviest).cbrt()).min(4.0)
            } else {
                1.0
            };
            let size = Some(Vec2::splat(view.size * scale));
            if sprite.color != color || sprite.custom_size != size {
                sprite.color = color;
                sprite.custom_size = size;
            }
        },
    );
}

//! Feature `render`: a sprite per fluid particle, tinted through a colour map by density, speed
//! or pressure, moved smoothly between fixed steps; a camera that keeps the tank in view. See
//! [`ParticleRenderPlugin`].

mod bodies;
mod colormap;
mod liquid;
mod solids;
mod view;

use crate::fluid::{Density, FluidMaterial, FluidParticle, Pressure, SphParams};
use crate::particle::{Position, Velocity};
use crate::schedule::{ParticleSchedule, ParticleSystems};
use bevy::asset::RenderAssetUsages;
use bevy::prelude::*;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat};

pub use bodies::{BodyColor, BodyView};
pub use colormap::{ColorMap, ColorRange, ColorTable};
pub use liquid::LiquidStyle;
pub(crate) use view::cursor_to_world;
pub use view::{ParticleCamera, ViewInsets};

/// Draws fluid particles as sprites and keeps a [`ParticleCamera`] framing the tank.
///
/// Every [`FluidParticle`] gets a round [`Sprite`] when it appears (it goes with the entity when
/// the particle is despawned). Each frame, after the fixed steps of that frame
/// ([`RunFixedMainLoopSystems::AfterFixedMainLoop`]):
/// - `Transform` is placed between the particle's last two fixed-step positions by
///   [`Time<Fixed>::overstep_fraction`], so motion is smooth at any display rate (the sprite
///   lags the simulation by at most one tick);
/// - the sprite colour shows the [`ParticleView`]'s quantity through its [`ColorMap`], over a
///   range that follows the data (quantiles, eased between frames) or is set by hand;
/// - cameras with [`ParticleCamera`] are fitted to the tank in the window area that
///   [`ViewInsets`] leaves free, so the tank fills the window at any size;
/// - [`Solid`](crate::fluid::Solid)s without a sprite or mesh of their own are drawn filled,
///   a colour each, darker below the waterline; the tank walls and the solids are outlined
///   with gizmos;
/// - gravity bodies that are not fluid particles get sprites too, tinted by speed or mass
///   ([`BodyView`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct ParticleRenderPlugin;

/// How fluid particles are drawn.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum ParticleDraw {
    /// A round sprite per particle, for inspecting the simulation.
    #[default]
    Sprites,
    /// A liquid with a surface (see [`LiquidStyle`]): the particles are splatted into a smooth
    /// field, and the body is where the field is above a threshold.
    Liquid,
}

impl ParticleDraw {
    /// Both, in menu order.
    pub const ALL: [ParticleDraw; 2] = [ParticleDraw::Sprites, ParticleDraw::Liquid];

    /// The name in menus.
    pub fn label(self) -> &'static str {
        match self {
            ParticleDraw::Sprites => "Particles",
            ParticleDraw::Liquid => "Liquid",
        }
    }
}

/// What the colours show (on sprites, or inside the liquid).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub enum RenderMode {
    /// Density, kg/m³.
    #[default]
    Density,
    /// Speed, m/s.
    Speed,
    /// Pressure, Pa.
    Pressure,
    /// One colour for every particle.
    Solid,
}

impl RenderMode {
    /// Every mode, in menu order.
    pub const ALL: [RenderMode; 4] = [
        RenderMode::Density,
        RenderMode::Speed,
        RenderMode::Pressure,
        RenderMode::Solid,
    ];

    /// The quantity's name.
    pub fn label(self) -> &'static str {
        match self {
            RenderMode::Density => "Density",
            RenderMode::Speed => "Speed",
            RenderMode::Pressure => "Pressure",
            RenderMode::Solid => "Solid colour",
        }
    }

    /// The quantity's unit.
    pub fn unit(self) -> &'static str {
        match self {
            RenderMode::Density => "kg/m³",
            RenderMode::Speed => "m/s",
            RenderMode::Pressure => "Pa",
            RenderMode::Solid => "",
        }
    }

    /// The quantiles an auto-scaled range spans: density and pressure ignore the thin
    /// free-surface layer (low density by construction) and the odd splash.
    fn quantiles(self) -> (f32, f32) {
        match self {
            RenderMode::Density => (0.05, 0.995),
            RenderMode::Speed => (0.0, 0.99),
            RenderMode::Pressure => (0.01, 0.99),
            RenderMode::Solid => (0.0, 1.0),
        }
    }
}

/// How particles are drawn; edit it live (the panel does).
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct ParticleView {
    /// Sprites or a liquid.
    pub draw: ParticleDraw,
    /// The quantity the colour shows ([`RenderMode::Solid`] in the liquid: its own colours).
    pub mode: RenderMode,
    /// The colour map.
    pub color_map: ColorMap,
    /// Follow the data: [`range`](Self::range) is updated every frame.
    pub auto_range: bool,
    /// The values at the map's two ends, in the mode's unit.
    pub range: ColorRange,
    /// The colour of [`RenderMode::Solid`].
    pub solid_color: Color,
    /// Sprite diameter, in particle spacings (soft-edged discs that overlap into a surface).
    pub sprite_scale: f32,
    /// Draw between fixed steps (off: draw at the last step).
    pub interpolate: bool,
    /// Outline the tank and the solids.
    pub outline: bool,
    /// Draw each solid filled, in a colour of its own, darker below its waterline (not one
    /// with a sprite or mesh of its own).
    pub fill_solids: bool,
}

impl Default for ParticleView {
    fn default() -> Self {
        Self {
            draw: ParticleDraw::Sprites,
            mode: RenderMode::Density,
            color_map: ColorMap::Blues,
            auto_range: true,
            range: ColorRange::new(950.0, 1050.0),
            solid_color: Color::srgb(0.2, 0.45, 0.9),
            sprite_scale: 1.8,
            interpolate: true,
            outline: true,
            fill_solids: true,
        }
    }
}

/// The particle's position at the previous fixed step, m: the start of the interpolation.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, Deref, DerefMut, PartialEq)]
#[reflect(Component, Default, Debug)]
pub struct PreviousPosition(pub Vec2);

/// The shared round texture of particle sprites.
#[derive(Resource, Debug, Clone)]
pub struct ParticleTexture(pub Handle<Image>);

/// The sprite layer of the render systems, after the fixed steps of each frame.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ParticleRenderSystems {
    /// Camera fitting.
    Camera,
    /// Transforms and colours.
    Sprites,
}

impl Plugin for ParticleRenderPlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<ParticleView>()
            .register_type::<BodyView>()
            .init_resource::<BodyView>()
            .add_observer(bodies::attach_body_sprite)
            .register_type::<PreviousPosition>()
            .init_resource::<ParticleView>()
            .init_resource::<ViewInsets>()
            .add_systems(PreStartup, create_particle_texture)
            .add_observer(attach_sprite)
            .configure_sets(
                RunFixedMainLoop,
                (
                    ParticleRenderSystems::Camera,
                    ParticleRenderSystems::Sprites,
                )
                    .chain()
                    .in_set(RunFixedMainLoopSystems::AfterFixedMainLoop),
            )
            .add_systems(
                RunFixedMainLoop,
                (
                    view::fit_cameras.in_set(ParticleRenderSystems::Camera),
                    (
                        update_color_range,
                        update_sprites,
                        liquid::update_liquid,
                        bodies::update_body_sprites,
                    )
                        .chain()
                        .in_set(ParticleRenderSystems::Sprites),
                ),
            )
            .add_systems(
                Update,
                (
                    draw_outlines,
                    draw_solids,
                    (solids::attach_fills, solids::update_fills).chain(),
                ),
            );
        liquid::build(app);
    }

    /// The fixed-step system goes into the particle schedule once every plugin is built, so the
    /// renderer follows [`ParticlePlugins`](crate::ParticlePlugins) added before or after it.
    fn finish(&self, app: &mut App) {
        let schedule = ParticleSchedule::of(app);
        app.add_systems(
            schedule,
            remember_previous_positions.in_set(ParticleSystems::Prepare),
        );
    }
}

/// Values the auto range takes its quantiles from (a sample of larger scenes).
const QUANTILE_SAMPLE: usize = 4096;

/// Texture side, px: enough for a smooth edge at the sizes particles are drawn.
const TEXTURE_SIZE: u32 = 32;

/// Alpha of the particle disc at `r` (0 centre, 1 rim): opaque core, soft rim.
fn disc_alpha(r: f32) -> f32 {
    let edge = ((1.0 - r) / 0.35).clamp(0.0, 1.0);
    edge * edge * (3.0 - 2.0 * edge)
}

fn create_particle_texture(mut commands: Commands, mut images: ResMut<Assets<Image>>) {
    let n = TEXTURE_SIZE;
    let mut data = Vec::with_capacity((n * n * 4) as usize);
    for y in 0..n {
        for x in 0..n {
            let centre = Vec2::splat(n as f32 / 2.0);
            let r = (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - centre).length() / centre.x;
            let a = (disc_alpha(r) * 255.0).round() as u8;
            data.extend_from_slice(&[255, 255, 255, a]);
        }
    }
    let image = Image::new(
        Extent3d {
            width: n,
            height: n,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    commands.insert_resource(ParticleTexture(images.add(image)));
}

/// Gives a new particle its sprite, placed at its position.
fn attach_sprite(
    add: On<Add, FluidParticle>,
    particles: Query<&Position>,
    texture: Option<Res<ParticleTexture>>,
    params: Res<SphParams>,
    view: Res<ParticleView>,
    mut commands: Commands,
) {
    let position = particles.get(add.entity).map(|p| p.0).unwrap_or_default();
    let size = Vec2::splat(view.sprite_scale * params.particle_spacing);
    let sprite = Sprite {
        image: texture.map(|t| t.0.clone()).unwrap_or_default(),
        custom_size: Some(size),
        color: view.solid_color,
        ..default()
    };
    commands.entity(add.entity).insert((
        sprite,
        Transform::from_translation(position.extend(0.0)),
        PreviousPosition(position),
        sprite_visibility(view.draw),
    ));
}

/// Sprites show in [`ParticleDraw::Sprites`] only.
fn sprite_visibility(draw: ParticleDraw) -> Visibility {
    match draw {
        ParticleDraw::Sprites => Visibility::Inherited,
        ParticleDraw::Liquid => Visibility::Hidden,
    }
}

fn remember_previous_positions(mut particles: Query<(&Position, &mut PreviousPosition)>) {
    particles
        .par_iter_mut()
        .for_each(|(position, mut previous)| {
            previous.set_if_neq(PreviousPosition(position.0));
        });
}

/// The value a particle shows in `mode`.
fn shown_value(
    mode: RenderMode,
    velocity: &Velocity,
    density: &Density,
    pressure: &Pressure,
) -> f32 {
    match mode {
        RenderMode::Density => density.0,
        RenderMode::Speed => velocity.length(),
        RenderMode::Pressure => pressure.0,
        RenderMode::Solid => 0.0,
    }
}

/// Auto-scaling: moves [`ParticleView::range`] towards the current quantiles (at once when
/// the mode changes).
fn update_color_range(
    mut view: ResMut<ParticleView>,
    particles: Query<(&Velocity, &Density, &Pressure), With<FluidParticle>>,
    mut values: Local<Vec<f32>>,
    mut last_mode: Local<Option<RenderMode>>,
) {
    if !view.auto_range || view.mode == RenderMode::Solid {
        return;
    }
    let mode = view.mode;
    // A sample is enough for quantiles ([`ColorRange::from_quantiles`] takes at most 4,096).
    let stride = particles.iter().len().div_ceil(QUANTILE_SAMPLE).max(1);
    values.clear();
    values.extend(
        particles
            .iter()
            .step_by(stride)
            .map(|(v, d, p)| shown_value(mode, v, d, p)),
    );
    let (low, high) = mode.quantiles();
    let Some(mut target) = ColorRange::from_quantiles(&values, low, high) else {
        return;
    };
    // Keep a visible spread when the field is uniform (a fluid at rest).
    let spread = match mode {
        RenderMode::Density => 0.01 * target.max.abs().max(1.0),
        RenderMode::Speed => 0.05,
        _ => 1.0,
    };
    if target.max - target.min < spread {
        let mid = 0.5 * (target.max + target.min);
        target = ColorRange::new(mid - 0.5 * spread, mid + 0.5 * spread);
        if mode == RenderMode::Speed {
            target = ColorRange::new(0.0, spread);
        }
    }
    let rate = if *last_mode == Some(mode) { 0.1 } else { 1.0 };
    *last_mode = Some(mode);
    let range = view.range.approach(target, rate);
    if range != view.range {
        view.range = range;
    }
}

/// What the sprite pass reads and writes per particle.
type SpriteData = (
    &'static Position,
    &'static PreviousPosition,
    &'static Velocity,
    &'static Density,
    &'static Pressure,
    &'static mut Transform,
    &'static mut Sprite,
    &'static mut Visibility,
    Option<&'static FluidMaterial>,
);

/// Interpolated transforms, colours and sizes, in parallel.
fn update_sprites(
    view: Res<ParticleView>,
    texture: Option<Res<ParticleTexture>>,
    params: Res<SphParams>,
    style: Res<LiquidStyle>,
    fixed: Res<Time<Fixed>>,
    mut table: Local<Option<(ColorMap, ColorTable)>>,
    mut particles: Query<SpriteData, With<FluidParticle>>,
) {
    let shown = sprite_visibility(view.draw);
    if view.draw == ParticleDraw::Liquid {
        // Hidden while the liquid draws: nothing else to update.
        if view.is_changed() {
            for item in &mut particles {
                let mut visibility = item.7;
                visibility.set_if_neq(shown);
            }
        }
        return;
    }
    if table.as_ref().is_none_or(|(map, _)| *map != view.color_map) {
        *table = Some((view.color_map, view.color_map.table(256)));
    }
    let Some((_, table)) = table.as_ref() else {
        return;
    };
    let alpha = if view.interpolate {
        fixed.overstep_fraction().clamp(0.0, 1.0)
    } else {
        1.0
    };
    let size = Some(Vec2::splat(view.sprite_scale * params.particle_spacing));
    let view = &*view;
    let texture = texture.as_deref().map(|t| &t.0);
    // Each liquid besides the base one in its liquid view's colour.
    let liquid_colors: Vec<Color> = (params.liquids.iter().enumerate())
        .map(|(k, liquid)| style.liquid_color(k + 1, &liquid.name))
        .collect();
    let solid = |material: Option<&FluidMaterial>| {
        let k = material.map_or(0, |m| m.0 as usize);
        k.checked_sub(1)
            .and_then(|i| liquid_colors.get(i))
            .copied()
            .unwrap_or(view.solid_color)
    };
    particles.par_iter_mut().for_each(
        |(
            position,
            previous,
            velocity,
            density,
            pressure,
            mut transform,
            mut sprite,
            mut visibility,
            material,
        )| {
            visibility.set_if_neq(shown);
            let at = previous.0.lerp(position.0, alpha).extend(0.0);
            if transform.translation != at {
                transform.translation = at;
            }
            let color = match view.mode {
                RenderMode::Solid => solid(material),
                mode => Color::LinearRgba(
                    table.map(shown_value(mode, velocity, density, pressure), view.range),
                ),
            };
            if sprite.color != color || sprite.custom_size != size {
                sprite.color = color;
                sprite.custom_size = size;
            }
            // A particle spawned before the texture existed.
            if let Some(texture) = texture
                && sprite.image != *texture
            {
                sprite.image = texture.clone();
            }
        },
    );
}

fn draw_outlines(view: Res<ParticleView>, params: Res<SphParams>, mut gizmos: Gizmos) {
    if !view.outline {
        return;
    }
    let color = Color::srgb(0.75, 0.8, 0.85);
    if let Some(tank) = params.tank {
        let size = tank.size();
        gizmos.rect_2d(Isometry2d::from_translation(0.5 * size), size, color);
    }
}

/// Outlines every [`Solid`](crate::fluid::Solid) at its pose, warm while it is in the water.
fn draw_solids(
    view: Res<ParticleView>,
    solids: Query<(&crate::fluid::Solid, &Transform, &crate::fluid::Submerged)>,
    mut gizmos: Gizmos,
) {
    if !view.outline {
        return;
    }
    for (solid, transform, submerged) in &solids {
        let color = if submerged.in_water {
            Color::srgb(0.95, 0.7, 0.35)
        } else {
            Color::srgb(0.8, 0.8, 0.75)
        };
        let angle = transform.rotation.to_euler(EulerRot::ZYX).0;
        let pose = Isometry2d::new(transform.translation.truncate(), Rot2::radians(angle));
        for part in &solid.shape.parts {
            let outline = part.outline(0.01);
            let closed = outline.iter().chain(outline.first()).map(|&p| pose * p);
            gizmos.linestrip_2d(closed, color);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn particle_disc_is_opaque_inside_and_clear_outside() {
        assert_eq!(disc_alpha(0.0), 1.0);
        assert_eq!(disc_alpha(0.6), 1.0);
        assert!(disc_alpha(0.85) > 0.0 && disc_alpha(0.85) < 1.0);
        assert_eq!(disc_alpha(1.0), 0.0);
        assert_eq!(disc_alpha(1.4), 0.0);
    }
}

//! Solids drawn as bodies: every [`Solid`] without a sprite or mesh of its own gets a filled
//! shape in a colour of its own, darker and bluer below its waterline, so a crate reads as a
//! crate riding in the water. Outlines stay an option ([`ParticleView::outline`]). See
//! [`ParticleRenderPlugin`](super::ParticleRenderPlugin).

use super::ParticleView;
use crate::fluid::{Pose, Solid, Submerged, pose_of};
use bevy::asset::RenderAssetUsages;
use bevy::camera::visibility::NoFrustumCulling;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

/// Depth of a body's dry fill: in front of the particle sprites (0) and the liquid surface.
const FILL_Z: f32 = 0.5;

/// Depth of its wet part, just in front of the dry fill.
const WET_Z: f32 = 0.51;

/// Body colours, one per solid by its entity (dry; the wet part mixes in [`WATER`]).
const PALETTE: [Srgba; 8] = [
    Srgba::rgb(0.72, 0.52, 0.30),
    Srgba::rgb(0.80, 0.33, 0.24),
    Srgba::rgb(0.30, 0.62, 0.58),
    Srgba::rgb(0.86, 0.68, 0.26),
    Srgba::rgb(0.50, 0.52, 0.66),
    Srgba::rgb(0.55, 0.62, 0.32),
    Srgba::rgb(0.78, 0.76, 0.70),
    Srgba::rgb(0.62, 0.42, 0.56),
];

/// What water does to a body's colour below the waterline.
const WATER: Srgba = Srgba::rgb(0.06, 0.20, 0.38);

/// How much of [`WATER`] the wet part takes.
const WET_MIX: f32 = 0.5;

/// One of the two fills of a solid: its whole shape (in the solid's frame, posed by the fill's
/// transform) or its part under water (in world coordinates, re-made every frame).
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct SolidFill {
    /// The solid drawn.
    solid: Entity,
    /// The part under water (else the whole shape).
    wet: bool,
}

/// Solids the fills draw: without a sprite or mesh of their own (and not a fill).
type DrawnSolid = (Without<SolidFill>, Without<Sprite>, Without<Mesh2d>);

/// Solids new or reshaped this frame, without a sprite or mesh of their own.
type NewUndrawnSolid = (Changed<Solid>, Without<Sprite>, Without<Mesh2d>);

/// Gives each new or reshaped [`Solid`] without a sprite or mesh of its own its two fills.
pub(super) fn attach_fills(
    solids: Query<(Entity, &Solid), NewUndrawnSolid>,
    fills: Query<(Entity, &SolidFill)>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<ColorMaterial>>,
    mut commands: Commands,
) {
    for (entity, solid) in &solids {
        for (fill, of) in &fills {
            if of.solid == entity {
                commands.entity(fill).despawn();
            }
        }
        let dry = PALETTE[palette_index(entity)];
        let wet = dry.mix(&WATER, WET_MIX);
        let shape = solid.shape.parts.iter();
        let whole = polygons_mesh(shape.map(|part| part.below(Pose::default(), f32::INFINITY)));
        if whole.count_vertices() == 0 {
            // A segment: no area to fill (its outline is drawn).
            continue;
        }
        // The wet fill starts as the whole shape, hidden until the first waterline.
        for (is_wet, mesh, color) in [(false, whole.clone(), dry), (true, whole, wet)] {
            commands.spawn((
                SolidFill {
                    solid: entity,
                    wet: is_wet,
                },
                Mesh2d(meshes.add(mesh)),
                MeshMaterial2d(materials.add(ColorMaterial::from_color(color))),
                Transform::from_xyz(0.0, 0.0, if is_wet { WET_Z } else { FILL_Z }),
                NoFrustumCulling,
                Name::new("solid fill"),
            ));
        }
    }
}

/// Follows each solid with its fills: the dry one at its pose, the wet one cut at the
/// waterline its [`Submerged::fraction`] gives; hides them with [`ParticleView::fill_solids`]
/// off, and despawns those whose solid is gone or got a sprite or mesh of its own.
pub(super) fn update_fills(
    view: Res<ParticleView>,
    solids: Query<(&Solid, &Transform, &Submerged), DrawnSolid>,
    mut fills: Query<(Entity, &SolidFill, &Mesh2d, &mut Transform, &mut Visibility)>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut commands: Commands,
) {
    for (fill, of, mesh, mut transform, mut visibility) in &mut fills {
        let Ok((solid, pose, submerged)) = solids.get(of.solid) else {
            commands.entity(fill).despawn();
            continue;
        };
        if !view.fill_solids {
            visibility.set_if_neq(Visibility::Hidden);
            continue;
        }
        if !of.wet {
            visibility.set_if_neq(Visibility::Inherited);
            let placed = Transform {
                translation: pose.translation.truncate().extend(FILL_Z),
                rotation: pose.rotation,
                scale: Vec3::ONE,
            };
            transform.set_if_neq(placed);
            continue;
        }
        let pose = pose_of(pose);
        let wet = waterline(solid, pose, submerged.fraction)
            .map(|level| {
                let parts = solid.shape.parts.iter();
                polygons_mesh(parts.map(move |part| part.below(pose, level)))
            })
            .filter(|wet| wet.count_vertices() > 0);
        visibility.set_if_neq(if wet.is_some() {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        });
        // An empty mesh upsets the renderer's allocator: a dry body keeps its last wet mesh,
        // hidden.
        if let (Some(wet), Some(mut mesh)) = (wet, meshes.get_mut(&mesh.0)) {
            *mesh = wet;
        }
    }
}

/// The level (world y, m) below which `fraction` of the solid's area lies at `pose` (what
/// [`Submerged`] measures), by bisection; `None` if none of it is under water.
fn waterline(solid: &Solid, pose: Pose, fraction: f32) -> Option<f32> {
    let area = solid.shape.area();
    if !(fraction > 0.0 && area > 0.0) {
        return None;
    }
    let whole = solid
        .shape
        .parts
        .iter()
        .flat_map(|part| part.below(pose, f32::INFINITY));
    let (mut low, mut high) = whole.fold((f32::INFINITY, f32::NEG_INFINITY), |(low, high), p| {
        (low.min(p.y), high.max(p.y))
    });
    if low >= high || low.is_nan() || fraction >= 1.0 {
        return Some(high);
    }
    let under = |level: f32| -> f32 {
        let parts = solid.shape.parts.iter();
        parts.map(|part| part.area_below(pose, level)).sum()
    };
    for _ in 0..24 {
        let middle = 0.5 * (low + high);
        if under(middle) < fraction * area {
            low = middle;
        } else {
            high = middle;
        }
    }
    Some(0.5 * (low + high))
}

/// A triangle mesh of convex polygons (each as a fan from its first corner).
fn polygons_mesh(polygons: impl Iterator<Item = Vec<Vec2>>) -> Mesh {
    let (mut positions, mut indices) = (Vec::<[f32; 3]>::new(), Vec::<u32>::new());
    for polygon in polygons.filter(|p| p.len() >= 3) {
        let first = positions.len() as u32;
        positions.extend(polygon.iter().map(|p| p.extend(0.0).to_array()));
        for k in 1..polygon.len() as u32 - 1 {
            indices.extend([first, first + k, first + k + 1]);
        }
    }
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    );
    mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    mesh.insert_indices(Indices::U32(indices));
    mesh
}

/// A solid's place in the palette, from its entity.
fn palette_index(entity: Entity) -> usize {
    (entity.to_bits().wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 61) as usize % PALETTE.len()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fluid::SolidShape;

    #[test]
    fn the_waterline_holds_the_submerged_fraction_below_it() {
        let solid = Solid::new(SolidShape::rectangle(0.2, 0.1));
        let pose = Pose {
            position: Vec2::new(1.0, 0.5),
            angle: 0.3,
        };
        for fraction in [0.1, 0.5, 0.9] {
            let level = waterline(&solid, pose, fraction).unwrap();
            let under = solid.shape.parts[0].area_below(pose, level);
            assert!(
                (under / solid.shape.area() - fraction).abs() < 1e-3,
                "{fraction}: {under}"
            );
        }
        assert_eq!(waterline(&solid, pose, 0.0), None);
    }

    #[test]
    fn a_fill_is_a_fan_of_triangles_per_polygon() {
        let square = vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let mesh = polygons_mesh([square.clone(), square, vec![Vec2::ZERO]].into_iter());
        assert_eq!(mesh.count_vertices(), 8);
        assert_eq!(mesh.indices().unwrap().len(), 12);
    }
}

//! The mouse tools on coupled bodies (feature `render`): pull, push and drag act on a dynamic
//! body as on the fluid, so the drag tool grabs a crate and carries it with the cursor.

use super::FluidCoupled;
use crate::fluid::Solid;
use crate::interact::{Pointer, PointerAction};
use avian2d::prelude as avian;
use avian2d::prelude::{ReadRigidBodyForces, WriteRigidBodyForces};
use bevy::prelude::*;

/// Applies the pointer's field to each dynamic coupled body, evaluated where the body is
/// nearest the cursor (at the cursor when it is inside the body) with the body's velocity.
pub(super) fn pointer_on_bodies(
    pointer: Option<Res<Pointer>>,
    mut bodies: Query<(&Solid, &avian::RigidBody, avian::Forces), With<FluidCoupled>>,
) {
    let Some(pointer) = pointer else {
        return;
    };
    let field = pointer.force;
    if field.action == PointerAction::None {
        return;
    }
    for (solid, body, mut forces) in &mut bodies {
        if !body.is_dynamic() {
            continue;
        }
        let (origin, rotation) = (forces.position().0, forces.rotation().as_radians());
        let turn = Rot2::radians(rotation);
        let local = turn.inverse() * (field.center - origin);
        let (distance, normal) = solid.shape.distance(local);
        let nearest = origin + turn * (local - distance.max(0.0) * normal);
        let a = field.acceleration(nearest, forces.linear_velocity());
        if a.is_finite() && a != Vec2::ZERO {
            forces.apply_linear_acceleration(a);
        }
    }
}

//! Pure view maths (fitting a region into a window, cursor to world) and the camera-fitting
//! system. See [`ParticleRenderPlugin`](crate::render::ParticleRenderPlugin).

use crate::fluid::SphParams;
use bevy::camera::ScalingMode;
use bevy::core_pipeline::tonemapping::DebandDither;
use bevy::prelude::*;
use bevy::render::view::Msaa;
use bevy::window::PrimaryWindow;

/// A 2D camera that the render plugin keeps fitted to the tank (with a margin): the tank fills
/// the window area left free by [`ViewInsets`], whatever the window's size.
///
/// It renders without multisampling: particles are soft-edged textures, which MSAA does not
/// smooth, and a software renderer (Mesa's lavapipe) pays for every sample.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component, Debug)]
#[require(Camera2d, Msaa = Msaa::Off, DebandDither = DebandDither::Disabled)]
pub struct ParticleCamera {
    /// Space kept around the tank, as a fraction of its larger side.
    pub margin: f32,
    /// Fit the camera every frame (turn off to pan and zoom it yourself).
    pub fit: bool,
    /// The world region to show, m; `None` shows the fluid's tank.
    pub region: Option<Rect>,
}

impl Default for ParticleCamera {
    fn default() -> Self {
        Self {
            margin: 0.04,
            fit: true,
            region: None,
        }
    }
}

/// Window edges covered by UI (logical px), which camera fitting leaves out: the panel sets
/// `left` to its width.
#[derive(Resource, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct ViewInsets {
    /// Covered at the left, px.
    pub left: f32,
    /// Covered at the right, px.
    pub right: f32,
    /// Covered at the top, px.
    pub top: f32,
    /// Covered at the bottom, px.
    pub bottom: f32,
}

/// The camera centre (world units) and scale (world units per logical pixel) that show `region`
/// as large as possible, centred, in the part of a `window`-sized viewport (px) that `insets`
/// leave free. `None` for an empty region or no free area.
pub fn fit_tank(region: Rect, window: Vec2, insets: ViewInsets) -> Option<(Vec2, f32)> {
    let free = Vec2::new(
        window.x - insets.left - insets.right,
        window.y - insets.top - insets.bottom,
    );
    let size = region.size();
    if !(free.x >= 1.0 && free.y >= 1.0 && size.x > 0.0 && size.y > 0.0) {
        return None;
    }
    let scale = (size.x / free.x).max(size.y / free.y);
    // Offset of the free area's centre from the window's centre, px (y down).
    let offset = Vec2::new(
        0.5 * (insets.left - insets.right),
        0.5 * (insets.top - insets.bottom),
    );
    let centre = region.center() - Vec2::new(offset.x, -offset.y) * scale;
    Some((centre, scale))
}

/// The world point under `cursor` (logical px from the viewport's top-left corner) for a camera
/// at `camera` whose orthographic projection spans `area` (camera space) over a viewport of
/// `viewport` px. Works for any pan, zoom and rotation of the camera.
pub fn cursor_to_world(cursor: Vec2, viewport: Vec2, area: Rect, camera: &GlobalTransform) -> Vec2 {
    let uv = cursor / viewport.max(Vec2::ONE);
    let local = Vec2::new(
        area.min.x + uv.x * area.width(),
        area.max.y - uv.y * area.height(),
    );
    camera.transform_point(local.extend(0.0)).truncate()
}

/// Keeps every fitted [`ParticleCamera`] framing the tank.
pub(crate) fn fit_cameras(
    params: Res<SphParams>,
    insets: Res<ViewInsets>,
    window: Single<&Window, With<PrimaryWindow>>,
    mut cameras: Query<(&ParticleCamera, &mut Projection, &mut Transform)>,
) {
    let window_size = Vec2::new(window.width(), window.height());
    for (camera, mut projection, mut transform) in &mut cameras {
        let region = match (camera.region, params.tank) {
            (Some(region), _) => region,
            (None, Some(tank)) => Rect::new(0.0, 0.0, tank.width, tank.height),
            (None, None) => continue,
        };
        if !camera.fit {
            continue;
        }
        let margin = camera.margin.max(0.0) * region.width().max(region.height());
        let region = region.inflate(margin);
        let Some((centre, scale)) = fit_tank(region, window_size, *insets) else {
            continue;
        };
        let translation = centre.extend(transform.translation.z);
        if transform.translation != translation {
            transform.translation = translation;
        }
        if let Projection::Orthographic(ortho) = &*projection {
            let fitted =
                matches!(ortho.scaling_mode, ScalingMode::WindowSize) && ortho.scale == scale;
            if fitted {
                continue;
            }
        }
        if let Projection::Orthographic(ortho) = &mut *projection {
            ortho.scaling_mode = ScalingMode::WindowSize;
            ortho.scale = scale;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tank_fills_the_free_area() {
        let region = Rect::new(0.0, 0.0, 2.0, 1.0);
        // A wide window: height limits, 1 m per 500 px.
        let (centre, scale) =
            fit_tank(region, Vec2::new(1600.0, 500.0), ViewInsets::default()).unwrap();
        assert_eq!(centre, Vec2::new(1.0, 0.5));
        assert!((scale - 1.0 / 500.0).abs() < 1e-9);
        // A 600 px panel on the left of a 1600 × 900 window leaves 1000 × 900: width limits, and
        // the tank centre moves right by half the panel.
        let insets = ViewInsets {
            left: 600.0,
            ..default()
        };
        let (centre, scale) = fit_tank(region, Vec2::new(1600.0, 900.0), insets).unwrap();
        assert!((scale - 2.0 / 1000.0).abs() < 1e-9);
        assert!((centre.x - (1.0 - 300.0 * scale)).abs() < 1e-6);
        assert_eq!(centre.y, 0.5);
        assert_eq!(fit_tank(region, Vec2::new(500.0, 500.0), insets), None);
        assert_eq!(
            fit_tank(Rect::default(), Vec2::splat(100.0), default()),
            None
        );
    }

    #[test]
    fn cursor_maps_to_world_under_pan_zoom_and_rotation() {
        // 800 × 600 viewport, 1 cm per px, camera at (3, 2).
        let viewport = Vec2::new(800.0, 600.0);
        let area = Rect::new(-4.0, -3.0, 4.0, 3.0);
        let camera = GlobalTransform::from_translation(Vec3::new(3.0, 2.0, 0.0));
        let at = |cursor: Vec2, camera: &GlobalTransform, area: Rect| {
            cursor_to_world(cursor, viewport, area, camera)
        };
        assert_eq!(
            at(Vec2::new(400.0, 300.0), &camera, area),
            Vec2::new(3.0, 2.0)
        );
        assert_eq!(at(Vec2::ZERO, &camera, area), Vec2::new(-1.0, 5.0));
        assert_eq!(at(viewport, &camera, area), Vec2::new(7.0, -1.0));
        // Zoomed in twice: half the area.
        let zoomed = Rect::new(-2.0, -1.5, 2.0, 1.5);
        assert_eq!(at(Vec2::ZERO, &camera, zoomed), Vec2::new(1.0, 3.5));
        // Rotated a quarter turn: screen right is world up.
        let rotated = GlobalTransform::from(
            Transform::from_xyz(3.0, 2.0, 0.0)
                .with_rotation(Quat::from_rotation_z(core::f32::consts::FRAC_PI_2)),
        );
        let p = at(Vec2::new(800.0, 300.0), &rotated, area);
        assert!((p - Vec2::new(3.0, 6.0)).length() < 1e-5, "{p}");
    }

    #[test]
    fn fitted_view_round_trips_the_cursor() {
        // What fit_tank chooses and cursor_to_world reads agree: the tank's corners land on the
        // free area's edges.
        let window = Vec2::new(1280.0, 720.0);
        let insets = ViewInsets {
            left: 300.0,
            ..default()
        };
        let region = Rect::new(0.0, 0.0, 1.6, 0.9);
        let (centre, scale) = fit_tank(region, window, insets).unwrap();
        let area = Rect::from_center_size(Vec2::ZERO, window * scale);
        let camera = GlobalTransform::from_translation(centre.extend(0.0));
        let free_centre = Vec2::new(300.0 + 0.5 * 980.0, 360.0);
        let p = cursor_to_world(free_centre, window, area, &camera);
        assert!((p - region.center()).length() < 1e-5, "{p}");
        let left_edge = cursor_to_world(Vec2::new(300.0, 360.0), window, area, &camera);
        assert!(left_edge.x <= 1e-5 && left_edge.x > -0.1, "{left_edge}");
    }
}

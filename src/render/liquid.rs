//! The liquid view ([`ParticleDraw::Liquid`]): every fluid particle is splatted as a smooth bump
//! into an off-screen field texture by a second camera (additive blending into a float target,
//! at a resolution tied to the window's), and a full-screen quad in front of the main
//! [`ParticleCamera`] turns the field into a liquid with its [`LiquidStyle`]. See
//! [`ParticleRenderPlugin`](super::ParticleRenderPlugin).
//!
//! The field at a point is `Σⱼ wⱼ (1 − r²/R²)³` over the particles within the splat radius `R`,
//! each weight `wⱼ = Δx² / (π R² / 4)` chosen so that the field is 1 inside a fluid at rest
//! (the bump's integral is `π R² / 4`). The surface is where the field crosses
//! [`LiquidStyle::threshold`]: two blobs merge where their fields add up, a jet one particle
//! wide stays connected (its field peaks at about `1.16 Δx / R` along it), and a lone droplet
//! shows as long as its peak `Δx² / (π R² / 4)` is above the threshold.

use super::{
    ParticleCamera, ParticleDraw, ParticleView, PreviousPosition, RenderMode, shown_value,
};
use crate::fluid::{Density, FluidMaterial, FluidParticle, Pressure, SphParams};
use crate::particle::{Position, Velocity};
use bevy::asset::{AssetPath, RenderAssetUsages, embedded_asset, embedded_path};
use bevy::camera::visibility::{NoFrustumCulling, RenderLayers};
use bevy::camera::{CameraProjection, CompositingSpace, Hdr, RenderTarget, ScalingMode};
use bevy::core_pipeline::tonemapping::DebandDither;
use bevy::image::{ImageSampler, ImageSamplerDescriptor};
use bevy::mesh::{Indices, MeshVertexBufferLayoutRef, PrimitiveTopology, VertexAttributeValues};
use bevy::prelude::*;
use bevy::render::render_resource::{
    AsBindGroup, BlendComponent, BlendFactor, BlendOperation, BlendState, Extent3d,
    RenderPipelineDescriptor, ShaderType, SpecializedMeshPipelineError, TextureDimension,
    TextureFormat,
};
use bevy::render::view::Msaa;
use bevy::shader::ShaderRef;
use bevy::sprite_render::{AlphaMode2d, Material2d, Material2dKey, Material2dPlugin};
use bevy::window::PrimaryWindow;

/// The render layer of the splats, which only the field camera sees.
const FIELD_LAYER: usize = 31;

/// Colour-map texels across.
const COLOR_MAP_TEXELS: u32 = 256;

/// How the liquid view looks; edit it live (the panel does).
#[derive(Resource, Reflect, Debug, Clone, PartialEq)]
#[reflect(Resource, Default, Debug)]
pub struct LiquidStyle {
    /// The field value at the surface, as a fraction of the field inside a fluid at rest.
    pub threshold: f32,
    /// Splat radius, in particle spacings.
    pub splat_radius: f32,
    /// Field texels per window pixel (the field is smooth: at 0.4 of the window's resolution it
    /// shows no steps and costs a sixth).
    pub resolution: f32,
    /// The body's colour just under the surface (its alpha: the body's opacity there).
    pub shallow_color: Color,
    /// The body's colour at [`depth`](Self::depth) and below.
    pub deep_color: Color,
    /// Depth of liquid above a point at which the body takes the deep colour, m.
    pub depth: f32,
    /// The rim's colour along the surface (its alpha: how strongly it shows).
    pub rim_color: Color,
    /// The rim's width, in particle spacings.
    pub rim_width: f32,
    /// The foam's colour where the flow is fast (its alpha: how strongly it shows).
    pub foam_color: Color,
    /// The speed at which the liquid is all foam, m/s (foam starts at a third of it).
    pub foam_speed: f32,
    /// The colours of the liquids besides the base one (`SphParams::liquids`, in order), just
    /// under the surface; they deepen as the base liquid's do. A liquid without one here takes
    /// [`liquid_color`](Self::liquid_color)'s choice for its name.
    pub liquid_colors: Vec<Color>,
}

impl Default for LiquidStyle {
    fn default() -> Self {
        Self::water()
    }
}

impl LiquidStyle {
    /// Water: clear blue that deepens to navy, a pale rim, white foam above 1 m/s.
    pub fn water() -> Self {
        Self {
            threshold: 0.25,
            splat_radius: 2.0,
            resolution: 0.4,
            shallow_color: Color::srgba(0.30, 0.62, 0.92, 0.92),
            deep_color: Color::srgba(0.05, 0.22, 0.52, 0.98),
            depth: 0.15,
            rim_color: Color::srgba(0.75, 0.90, 1.0, 0.8),
            rim_width: 0.8,
            foam_color: Color::srgba(0.92, 0.97, 1.0, 0.85),
            foam_speed: 3.0,
            liquid_colors: Vec::new(),
        }
    }

    /// The most liquids the view tells apart (the base one included); the rest take the last
    /// one's colour.
    pub const MAX_LIQUIDS: usize = 8;

    /// The colour of liquid `k` (1 the first of `SphParams::liquids`) called `name`, just under
    /// the surface: [`liquid_colors`](Self::liquid_colors)' if it has one, else amber for oil,
    /// green for brine and a colour of a small palette for any other.
    pub fn liquid_color(&self, k: usize, name: &str) -> Color {
        if let Some(&color) = k.checked_sub(1).and_then(|i| self.liquid_colors.get(i)) {
            return color;
        }
        let name = name.to_lowercase();
        if name.contains("oil") {
            Color::srgba(0.96, 0.74, 0.16, 0.95)
        } else if name.contains("brine") || name.contains("salt") {
            Color::srgba(0.16, 0.70, 0.52, 0.95)
        } else {
            const PALETTE: [(f32, f32, f32); 4] = [
                (0.86, 0.30, 0.36),
                (0.60, 0.40, 0.86),
                (0.95, 0.55, 0.20),
                (0.45, 0.80, 0.25),
            ];
            let (r, g, b) = PALETTE[k % PALETTE.len()];
            Color::srgba(r, g, b, 0.95)
        }
    }

    /// Honey: amber that deepens to brown, a golden rim, no foam.
    pub fn honey() -> Self {
        Self {
            shallow_color: Color::srgba(0.98, 0.72, 0.18, 0.95),
            deep_color: Color::srgba(0.62, 0.30, 0.04, 1.0),
            rim_color: Color::srgba(1.0, 0.88, 0.45, 0.9),
            foam_color: Color::srgba(1.0, 0.9, 0.6, 0.0),
            ..Self::water()
        }
    }
}

/// Adds the liquid view to [`ParticleRenderPlugin`](super::ParticleRenderPlugin).
pub(crate) fn build(app: &mut App) {
    embedded_asset!(app, "shaders/splat.wgsl");
    embedded_asset!(app, "shaders/liquid.wgsl");
    app.add_plugins((
        Material2dPlugin::<SplatMaterial>::default(),
        Material2dPlugin::<LiquidMaterial>::default(),
    ))
    .register_type::<LiquidStyle>()
    .init_resource::<LiquidStyle>()
    .add_systems(Update, spawn_liquid_view)
    .add_systems(
        PostUpdate,
        follow_camera
            .before(bevy::camera::CameraUpdateSystems)
            .before(bevy::transform::TransformSystems::Propagate),
    );
}

/// The entities and assets of the liquid view of the first [`ParticleCamera`].
#[derive(Resource, Debug, Clone)]
pub(crate) struct LiquidView {
    camera: Entity,
    field_camera: Entity,
    surface: Entity,
    field: Handle<Image>,
    color_map: Handle<Image>,
    splats: Handle<Mesh>,
    material: Handle<LiquidMaterial>,
    /// The colour map the texture holds.
    map_in_texture: super::ColorMap,
    /// The splats' bounds (world, m): the surface quad covers them and no more.
    bounds: Rect,
}

/// The splats' material: additive, no depth order (see `splat.wgsl`).
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone, Default)]
pub(crate) struct SplatMaterial {}

impl Material2d for SplatMaterial {
    fn fragment_shader() -> ShaderRef {
        embedded_shader(embedded_path!("shaders/splat.wgsl"))
    }

    fn alpha_mode(&self) -> AlphaMode2d {
        AlphaMode2d::Blend
    }

    fn specialize(
        descriptor: &mut RenderPipelineDescriptor,
        _layout: &MeshVertexBufferLayoutRef,
        _key: Material2dKey<Self>,
    ) -> Result<(), SpecializedMeshPipelineError> {
        let add = BlendComponent {
            src_factor: BlendFactor::One,
            dst_factor: BlendFactor::One,
            operation: BlendOperation::Add,
        };
        if let Some(fragment) = descriptor.fragment.as_mut() {
            for target in fragment.targets.iter_mut().flatten() {
                target.blend = Some(BlendState {
                    color: add,
                    alpha: add,
                });
            }
        }
        Ok(())
    }
}

/// The uniforms of `liquid.wgsl`.
#[derive(ShaderType, Debug, Clone, Copy, Default)]
pub(crate) struct LiquidUniform {
    shallow: Vec4,
    deep: Vec4,
    rim: Vec4,
    foam: Vec4,
    /// Threshold, rim width (px), foam speed (m/s), depth (texture heights).
    shape: Vec4,
    /// x: 1 to colour through the colour map; y: 1 to colour each liquid its own.
    options: Vec4,
    /// Each liquid's colour under the surface and deep down, by its rank in rest density.
    shallows: [Vec4; LiquidStyle::MAX_LIQUIDS],
    deeps: [Vec4; LiquidStyle::MAX_LIQUIDS],
}

/// The surface quad's material (see `liquid.wgsl`).
#[derive(Asset, TypePath, AsBindGroup, Debug, Clone)]
pub(crate) struct LiquidMaterial {
    #[uniform(0)]
    settings: LiquidUniform,
    #[texture(1)]
    #[sampler(2)]
    field: Handle<Image>,
    #[texture(3)]
    #[sampler(4)]
    color_map: Handle<Image>,
}

impl Material2d for LiquidMaterial {
    fn fragment_shader() -> ShaderRef {
        embedded_shader(embedded_path!("shaders/liquid.wgsl"))
    }

    fn alpha_mode(&self) -> AlphaMode2d {
        AlphaMode2d::Blend
    }
}

/// A shader embedded with `embedded_asset!`.
fn embedded_shader(path: std::path::PathBuf) -> ShaderRef {
    ShaderRef::Path(AssetPath::from_path_buf(path).with_source("embedded"))
}

fn linear_sampler() -> ImageSampler {
    ImageSampler::Descriptor(ImageSamplerDescriptor::linear())
}

/// An empty field texture of `size` texels.
fn field_image(size: UVec2) -> Image {
    let mut image = Image::new_target_texture(
        size.x.max(1),
        size.y.max(1),
        TextureFormat::Rgba16Float,
        None,
    );
    image.sampler = linear_sampler();
    image
}

/// The colour map as a texture one texel high, sRGB.
fn color_map_image(map: super::ColorMap) -> Image {
    let data = (0..COLOR_MAP_TEXELS)
        .flat_map(|i| {
            let t = i as f32 / (COLOR_MAP_TEXELS - 1) as f32;
            map.sample(t).to_srgba().to_u8_array()
        })
        .collect();
    let mut image = Image::new(
        Extent3d {
            width: COLOR_MAP_TEXELS,
            height: 1,
            depth_or_array_layers: 1,
        },
        TextureDimension::D2,
        data,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::default(),
    );
    image.sampler = linear_sampler();
    image
}

/// Spawns the liquid view for the first [`ParticleCamera`]: the field camera, the splat mesh and
/// the surface quad. Runs in `Update`, a frame after the camera appears, so that a UI plugin
/// that attaches itself to the first camera (bevy_egui) finds the main one.
#[expect(
    clippy::too_many_arguments,
    reason = "a Bevy system: one parameter per resource and query it reads"
)]
fn spawn_liquid_view(
    view: Option<Res<LiquidView>>,
    cameras: Query<Entity, With<ParticleCamera>>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut splat_materials: ResMut<Assets<SplatMaterial>>,
    mut liquid_materials: ResMut<Assets<LiquidMaterial>>,
    particle_view: Res<ParticleView>,
    mut commands: Commands,
) {
    if view.is_some_and(|v| cameras.contains(v.camera)) {
        return;
    }
    let Some(camera) = cameras.iter().next() else {
        return;
    };
    let field = images.add(field_image(UVec2::ONE));
    let color_map = images.add(color_map_image(particle_view.color_map));
    let layer = RenderLayers::layer(FIELD_LAYER);
    let field_camera = commands
        .spawn((
            Camera2d,
            Camera {
                order: -1,
                clear_color: ClearColorConfig::Custom(Color::NONE),
                is_active: false,
                ..default()
            },
            RenderTarget::Image(field.clone().into()),
            Hdr,
            CompositingSpace::Linear,
            Msaa::Off,
            DebandDither::Disabled,
            layer.clone(),
            Name::new("liquid field camera"),
        ))
        .id();
    let mut mesh = Mesh::new(
        PrimitiveTopology::TriangleList,
        RenderAssetUsages::default(),
    );
    write_splats(&mut mesh, core::iter::empty(), 0.0);
    let splats = meshes.add(mesh);
    commands.spawn((
        Mesh2d(splats.clone()),
        MeshMaterial2d(splat_materials.add(SplatMaterial {})),
        Transform::default(),
        NoFrustumCulling,
        layer,
        Name::new("liquid splats"),
    ));
    let material = liquid_materials.add(LiquidMaterial {
        settings: LiquidUniform::default(),
        field: field.clone(),
        color_map: color_map.clone(),
    });
    let surface = commands
        .spawn((
            Mesh2d(meshes.add(Rectangle::new(1.0, 1.0))),
            MeshMaterial2d(material.clone()),
            Transform::default(),
            Visibility::Hidden,
            NoFrustumCulling,
            Name::new("liquid surface"),
        ))
        .id();
    commands.insert_resource(LiquidView {
        camera,
        field_camera,
        surface,
        field,
        color_map,
        splats,
        material,
        map_in_texture: particle_view.color_map,
        bounds: Rect::default(),
    });
}

/// Keeps the field camera on the main camera's view (same transform, same visible area), the
/// field texture at [`LiquidStyle::resolution`] of the window, the surface quad over the view,
/// and turns the view on or off with [`ParticleView::draw`].
fn follow_camera(
    view: Option<Res<LiquidView>>,
    particle_view: Res<ParticleView>,
    style: Res<LiquidStyle>,
    mut cameras: Query<(&mut Camera, &mut Transform, &mut Projection), Without<Mesh2d>>,
    mut surfaces: Query<(&mut Transform, &mut Visibility), With<Mesh2d>>,
    mut images: ResMut<Assets<Image>>,
    mut materials: ResMut<Assets<LiquidMaterial>>,
) {
    let Some(view) = view else {
        return;
    };
    let on = particle_view.draw == ParticleDraw::Liquid;
    let Ok((camera, transform, projection)) = cameras.get(view.camera) else {
        return;
    };
    let (Some(viewport), Projection::Orthographic(ortho)) =
        (camera.physical_viewport_size(), projection)
    else {
        return;
    };
    let logical = camera.logical_viewport_size().unwrap_or(viewport.as_vec2());
    // The main camera's visible area this frame (its projection updates later in this stage).
    let mut fitted = ortho.clone();
    fitted.update(logical.x, logical.y);
    let area = fitted.area;
    let transform = *transform;
    let mut field_projection = ortho.clone();
    field_projection.scaling_mode = ScalingMode::Fixed {
        width: area.width(),
        height: area.height(),
    };
    field_projection.scale = 1.0;
    let texels = (viewport.as_vec2() * style.resolution.clamp(0.05, 1.0))
        .round()
        .as_uvec2()
        .max(UVec2::ONE);
    if let Ok((mut field_camera, mut field_transform, mut projection)) =
        cameras.get_mut(view.field_camera)
    {
        field_camera.is_active = on;
        field_transform.set_if_neq(transform);
        let (width, height) = (area.width(), area.height());
        let same = matches!(
            &*projection,
            Projection::Orthographic(p)
                if matches!(p.scaling_mode, ScalingMode::Fixed { width: w, height: h } if w == width && h == height)
                    && p.viewport_origin == field_projection.viewport_origin
        );
        if !same {
            *projection = Projection::Orthographic(field_projection);
        }
    }
    if on
        && let Some(image) = images.get(&view.field)
        && image.size() != texels
        && let Some(mut image) = images.get_mut(&view.field)
    {
        *image = field_image(texels);
        // The surface samples the new texture.
        materials.get_mut(&view.material);
    }
    if let Ok((mut surface, mut visibility)) = surfaces.get_mut(view.surface) {
        // Over the splats' bounds only: the pixels outside cannot be liquid.
        let bounds = view.bounds;
        let placed = Transform {
            translation: bounds.center().extend(transform.translation.z - 1.0),
            rotation: Quat::IDENTITY,
            scale: bounds.size().max(Vec2::splat(1e-6)).extend(1.0),
        };
        surface.set_if_neq(placed);
        visibility.set_if_neq(if on {
            Visibility::Visible
        } else {
            Visibility::Hidden
        });
    }
}

/// What the splat pass reads per particle.
pub(crate) type SplatData = (
    &'static Position,
    &'static PreviousPosition,
    &'static Velocity,
    &'static Density,
    &'static Pressure,
    Option<&'static FluidMaterial>,
);

/// Each material's rank among the liquids by rest density (the base liquid's 0 with one
/// liquid), capped at the view's last: where two liquids meet, the field's material average
/// lies between neighbouring ranks, and the surface shader snaps it to the nearer.
fn ranks(params: &SphParams) -> Vec<f32> {
    let mut order: Vec<usize> = (0..=params.liquids.len()).collect();
    let density = |k: usize| match k {
        0 => params.rest_density,
        k => params.liquids[k - 1].rest_density,
    };
    order.sort_by(|&a, &b| density(a).total_cmp(&density(b)));
    let mut rank = vec![0.0; order.len()];
    for (r, &k) in order.iter().enumerate() {
        rank[k] = r.min(LiquidStyle::MAX_LIQUIDS - 1) as f32;
    }
    rank
}

/// Rebuilds the splat mesh from the particles (four vertices each, at their interpolated
/// positions, carrying weight, speed and colour-map position), and the surface material from
/// the [`LiquidStyle`] and [`ParticleView`] when they change. Reuses the mesh's buffers: no
/// allocation once the particle count stops growing.
#[expect(
    clippy::too_many_arguments,
    reason = "a Bevy system: one parameter per resource and query it reads"
)]
pub(crate) fn update_liquid(
    view: Option<ResMut<LiquidView>>,
    particle_view: Res<ParticleView>,
    style: Res<LiquidStyle>,
    params: Res<SphParams>,
    fixed: Res<Time<Fixed>>,
    particles: Query<SplatData, With<FluidParticle>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<LiquidMaterial>>,
    mut images: ResMut<Assets<Image>>,
    windows: Query<&Window, With<PrimaryWindow>>,
    cameras: Query<&Projection, With<ParticleCamera>>,
) {
    let Some(mut view) = view else {
        return;
    };
    if particle_view.draw != ParticleDraw::Liquid {
        return;
    }
    let spacing = params.particle_spacing;
    let radius = style.splat_radius.max(0.5) * spacing;
    let weight = spacing * spacing / (core::f32::consts::PI * radius * radius / 4.0);
    let alpha = if particle_view.interpolate {
        fixed.overstep_fraction().clamp(0.0, 1.0)
    } else {
        1.0
    };
    let mode = particle_view.mode;
    let range = particle_view.range;
    let rank = ranks(&params);
    let rank_of = |m: Option<&FluidMaterial>| {
        m.and_then(|m| rank.get(m.0 as usize))
            .copied()
            .unwrap_or(rank[0])
    };
    if let Some(mut mesh) = meshes.get_mut(&view.splats) {
        view.bounds = write_splats(
            &mut mesh,
            particles.iter().map(|(position, previous, v, rho, p, m)| {
                let at = previous.0.lerp(position.0, alpha);
                let value = match mode {
                    RenderMode::Solid => 0.0,
                    mode => range.normalize(shown_value(mode, v, rho, p)),
                };
                let material = weight * rank_of(m);
                (at, [weight, weight * v.length(), weight * value, material])
            }),
            radius,
        );
    }
    if view.map_in_texture != particle_view.color_map
        && let Some(mut image) = images.get_mut(&view.color_map)
    {
        *image = color_map_image(particle_view.color_map);
        view.map_in_texture = particle_view.color_map;
    }
    // The view's height (m) and metres per screen pixel (for the rim's width in pixels).
    let view_height = match cameras.get(view.camera) {
        Ok(Projection::Orthographic(ortho)) => ortho.area.height().max(1e-6),
        _ => 1.0,
    };
    let metres_per_pixel = windows
        .single()
        .map_or(spacing, |w| view_height / w.height().max(1.0));
    let mut settings = liquid_uniform(&style, mode, spacing, view_height, metres_per_pixel);
    if !params.liquids.is_empty() && mode == RenderMode::Solid {
        color_liquids(&mut settings, &style, &params, &rank);
    }
    if let Some(material) = materials.get(&view.material)
        && material.settings != settings
        && let Some(mut material) = materials.get_mut(&view.material)
    {
        material.settings = settings;
    }
}

/// The surface shader's settings from the style, the colouring `mode`, the particle `spacing`
/// (m), the view's height (m) and its metres per screen pixel.
fn liquid_uniform(
    style: &LiquidStyle,
    mode: RenderMode,
    spacing: f32,
    view_height: f32,
    metres_per_pixel: f32,
) -> LiquidUniform {
    LiquidUniform {
        shallow: style.shallow_color.to_linear().to_vec4(),
        deep: style.deep_color.to_linear().to_vec4(),
        rim: style.rim_color.to_linear().to_vec4(),
        foam: style.foam_color.to_linear().to_vec4(),
        shape: Vec4::new(
            style.threshold,
            (style.rim_width * spacing / metres_per_pixel).max(0.5),
            style.foam_speed.max(1e-3),
            style.depth / view_height,
        ),
        options: Vec4::new(
            if mode == RenderMode::Solid { 0.0 } else { 1.0 },
            0.0,
            0.0,
            0.0,
        ),
        shallows: [Vec4::ZERO; LiquidStyle::MAX_LIQUIDS],
        deeps: [Vec4::ZERO; LiquidStyle::MAX_LIQUIDS],
    }
}

/// Sets each liquid's colours in `settings` by its rank, and switches them on: the base liquid
/// the style's own, the others [`LiquidStyle::liquid_color`] deepened as the base liquid's is.
fn color_liquids(
    settings: &mut LiquidUniform,
    style: &LiquidStyle,
    params: &SphParams,
    rank: &[f32],
) {
    let base = (
        style.shallow_color.to_linear(),
        style.deep_color.to_linear(),
    );
    let darken = Vec4::new(
        base.1.red / base.0.red.max(1e-3),
        base.1.green / base.0.green.max(1e-3),
        base.1.blue / base.0.blue.max(1e-3),
        1.0,
    )
    .min(Vec4::ONE);
    for (k, &r) in rank.iter().enumerate() {
        let (shallow, deep) = if k == 0 {
            (base.0.to_vec4(), base.1.to_vec4())
        } else {
            let name = &params.liquids[k - 1].name;
            let shallow = style.liquid_color(k, name).to_linear().to_vec4();
            let deep = (shallow * (0.5 + 0.5 * darken)).with_w(base.1.alpha);
            (shallow, deep)
        };
        settings.shallows[r as usize] = shallow;
        settings.deeps[r as usize] = deep;
    }
    settings.options.y = 1.0;
}

impl PartialEq for LiquidUniform {
    fn eq(&self, other: &Self) -> bool {
        (
            self.shallow,
            self.deep,
            self.rim,
            self.foam,
            self.shape,
            self.options,
            self.shallows,
            self.deeps,
        ) == (
            other.shallow,
            other.deep,
            other.rim,
            other.foam,
            other.shape,
            other.options,
            other.shallows,
            other.deeps,
        )
    }
}

/// Writes one quad of half-size `radius` per `(centre, colour)` into `mesh`'s buffers, keeping
/// their allocations (the indices only change with the count), and returns the quads' bounds.
fn write_splats(
    mesh: &mut Mesh,
    splats: impl Iterator<Item = (Vec2, [f32; 4])>,
    radius: f32,
) -> Rect {
    const CORNERS: [Vec2; 4] = [
        Vec2::new(-1.0, -1.0),
        Vec2::new(1.0, -1.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(-1.0, 1.0),
    ];
    const UVS: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let mut positions = take_attribute(mesh, Mesh::ATTRIBUTE_POSITION);
    let mut colors = take_attribute(mesh, Mesh::ATTRIBUTE_COLOR);
    let (VertexAttributeValues::Float32x3(p), VertexAttributeValues::Float32x4(c)) =
        (&mut positions, &mut colors)
    else {
        return Rect::default();
    };
    p.clear();
    c.clear();
    let mut bounds = Rect {
        min: Vec2::INFINITY,
        max: Vec2::NEG_INFINITY,
    };
    for (centre, color) in splats {
        bounds.min = bounds.min.min(centre);
        bounds.max = bounds.max.max(centre);
        for corner in CORNERS {
            p.push((centre + radius * corner).extend(0.0).to_array());
            c.push(color);
        }
    }
    if p.is_empty() {
        // One quad of zero weight: the mesh is never empty (the renderer allocates nothing for
        // an empty vertex buffer and then complains when asked to fill it).
        p.extend(CORNERS.map(|corner| (radius * corner).extend(0.0).to_array()));
        c.extend([[0.0; 4]; 4]);
    }
    let quads = p.len() / 4;
    mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, colors);
    let uv_quads = mesh
        .attribute(Mesh::ATTRIBUTE_UV_0)
        .map_or(0, |uv| uv.len() / 4);
    if uv_quads != quads {
        let uvs: Vec<[f32; 2]> = (0..quads).flat_map(|_| UVS).collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_UV_0, uvs);
        let indices = (0..quads as u32)
            .flat_map(|q| [0, 1, 2, 0, 2, 3].map(|k| 4 * q + k))
            .collect();
        mesh.insert_indices(Indices::U32(indices));
    }
    if bounds.is_empty() {
        Rect::default()
    } else {
        bounds.inflate(radius)
    }
}

/// Takes `attribute`'s values out of `mesh` (an empty list of the right kind if it has none).
fn take_attribute(
    mesh: &mut Mesh,
    attribute: bevy::mesh::MeshVertexAttribute,
) -> VertexAttributeValues {
    mesh.remove_attribute(attribute)
        .unwrap_or_else(|| match attribute.format {
            bevy::mesh::VertexFormat::Float32x3 => VertexAttributeValues::Float32x3(Vec::new()),
            _ => VertexAttributeValues::Float32x4(Vec::new()),
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The field of a lattice at rest, from the same bump and weight as the splats, at a point
    /// between particles: about one.
    #[test]
    fn field_inside_a_fluid_at_rest_is_one() {
        let dx = 0.01f32;
        let radius = 2.0 * dx;
        let weight = dx * dx / (core::f32::consts::PI * radius * radius / 4.0);
        let at = Vec2::new(0.3 * dx, 0.7 * dx);
        let mut field = 0.0;
        for i in -10..=10 {
            for j in -10..=10 {
                let r2 =
                    (Vec2::new(i as f32, j as f32) * dx - at).length_squared() / (radius * radius);
                if r2 < 1.0 {
                    field += weight * (1.0 - r2).powi(3);
                }
            }
        }
        assert!((field - 1.0).abs() < 0.03, "field {field}");
        // A lone droplet peaks at the weight, above the default threshold.
        assert!(weight > LiquidStyle::water().threshold, "peak {weight}");
    }

    #[test]
    fn splats_reuse_the_mesh_buffers() {
        let mut mesh = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        );
        mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, Vec::<[f32; 3]>::new());
        mesh.insert_attribute(Mesh::ATTRIBUTE_COLOR, Vec::<[f32; 4]>::new());
        let splats = |n: usize| (0..n).map(|i| (Vec2::splat(i as f32), [1.0; 4]));
        let bounds = write_splats(&mut mesh, splats(3), 0.5);
        assert_eq!(bounds, Rect::new(-0.5, -0.5, 2.5, 2.5));
        assert_eq!(mesh.count_vertices(), 12);
        assert_eq!(mesh.indices().map(|i| i.len()), Some(18));
        let first = mesh
            .attribute(Mesh::ATTRIBUTE_POSITION)
            .unwrap()
            .get_bytes()
            .as_ptr();
        write_splats(&mut mesh, splats(3), 0.5);
        let again = mesh
            .attribute(Mesh::ATTRIBUTE_POSITION)
            .unwrap()
            .get_bytes()
            .as_ptr();
        assert_eq!(first, again, "the position buffer was reallocated");
        let Some(VertexAttributeValues::Float32x3(p)) = mesh.attribute(Mesh::ATTRIBUTE_POSITION)
        else {
            panic!("positions");
        };
        assert_eq!(p[8], [1.5, 1.5, 0.0]);
        assert_eq!(p[10], [2.5, 2.5, 0.0]);
    }
}

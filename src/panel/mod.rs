//! Feature `egui`: the tweak panel — every fluid parameter live, presets, scenarios, render and
//! tool settings, statistics, pause/step/reset. See [`ParticlePanelPlugin`].

mod widgets;

use crate::control::{ResetSimulation, SimulationControl};
use crate::fluid::{
    FluidMaterial, KernelKind, Liquid, MAX_DENSITY_RATIO, PressureSolver, SphParams,
    SphParamsStatus, SphStats,
};
use crate::gameplay::{LoadSlot, SaveSlot, ScenarioKind, SnapshotSlot, SphScenario};
use crate::gravity::{GravityParams, GravityStats, Multipole};
use crate::interact::{Pointer, PointerSettings, PointerTool};
use crate::params::{ParamField, ParamTable};
use crate::render::{
    BodyColor, BodyView, ColorMap, LiquidStyle, ParticleDraw, ParticleView, RenderMode, ViewInsets,
};
use bevy::prelude::*;
use bevy_egui::input::EguiWantsInput;
use bevy_egui::{EguiContexts, EguiPlugin, EguiPrimaryContextPass, egui};
use widgets::{color_bar, enum_combo, param_slider, slider, stat_grid};

/// The egui tweak panel, docked on the left of the window.
///
/// It edits [`SphParams`], [`SphScenario`], [`ParticleView`] and [`PointerSettings`] directly
/// (the fluid validates every change before using it, and the panel shows a refused one in
/// red), drives [`SimulationControl`] and [`ResetSimulation`], and shows [`SphStats`]. While the
/// pointer or keyboard is over the panel, the mouse tools and key bindings ignore it; the
/// camera keeps the tank in the part of the window the panel leaves free ([`ViewInsets`]).
///
/// Adds [`EguiPlugin`] if the app has none, and a default [`SphScenario`] (the dam break) if the
/// app has none, for its scenario menu and reset button.
#[derive(Debug, Clone, Copy, Default)]
pub struct ParticlePanelPlugin;

impl Plugin for ParticlePanelPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<EguiPlugin>() {
            app.add_plugins(EguiPlugin::default());
        }
        // The panel edits these; the other plugins normally create them, but it works alone too.
        app.init_resource::<PanelState>()
            .init_resource::<SphScenario>()
            .init_resource::<ParticleView>()
            .init_resource::<LiquidStyle>()
            .init_resource::<SnapshotSlot>()
            .init_resource::<PointerSettings>()
            .init_resource::<Pointer>()
            .init_resource::<ViewInsets>()
            .init_resource::<SimulationControl>()
            .add_systems(PreUpdate, share_input_focus)
            .add_systems(EguiPrimaryContextPass, panel);
    }
}

/// Whether the panel is open, and rates measured between frames.
#[derive(Resource, Debug, Clone)]
pub struct PanelState {
    /// Show the panel (toggle with `Tab`).
    pub open: bool,
    rates: Rates,
}

impl Default for PanelState {
    fn default() -> Self {
        Self {
            open: true,
            rates: Rates::default(),
        }
    }
}

/// Frame and simulation rates, eased over frames.
#[derive(Debug, Clone, Copy, Default)]
struct Rates {
    fps: f32,
    substeps_per_s: f32,
    sim_speed: f32,
    last_substeps: u64,
    last_time: f64,
}

impl Rates {
    fn update(&mut self, dt: f32, stats: &SphStats) {
        if dt <= 0.0 {
            return;
        }
        let ease = |old: f32, new: f32| {
            if old == 0.0 {
                new
            } else {
                old + 0.05 * (new - old)
            }
        };
        let substeps = stats.total_substeps.saturating_sub(self.last_substeps) as f32 / dt;
        let sim = ((stats.time - self.last_time).max(0.0) as f32) / dt;
        self.fps = ease(self.fps, 1.0 / dt);
        self.substeps_per_s = ease(self.substeps_per_s, substeps);
        self.sim_speed = ease(self.sim_speed, sim);
        self.last_substeps = stats.total_substeps;
        self.last_time = stats.time;
    }
}

/// Tells the tools whether egui has the pointer or keyboard. The docked panel is drawn on egui's
/// background layer, which egui does not count as an area under the pointer, so the pointer is
/// also over the UI wherever it is over the panel's strip of the window ([`ViewInsets`]).
fn share_input_focus(
    wants: Res<EguiWantsInput>,
    insets: Res<ViewInsets>,
    window: Option<Single<&Window, With<bevy::window::PrimaryWindow>>>,
    mut pointer: ResMut<Pointer>,
) {
    let over_panel = window
        .and_then(|window| window.cursor_position())
        .is_some_and(|cursor| cursor.x < insets.left);
    let over_ui = wants.wants_any_pointer_input() || over_panel;
    let keyboard = wants.wants_any_keyboard_input();
    if pointer.over_ui != over_ui || pointer.ui_has_keyboard != keyboard {
        pointer.over_ui = over_ui;
        pointer.ui_has_keyboard = keyboard;
    }
}

/// Everything the panel reads and edits.
#[derive(bevy::ecs::system::SystemParam)]
struct PanelData<'w> {
    params: ResMut<'w, SphParams>,
    status: Res<'w, SphParamsStatus>,
    stats: Res<'w, SphStats>,
    scenario: ResMut<'w, SphScenario>,
    view: ResMut<'w, ParticleView>,
    tools: ResMut<'w, PointerSettings>,
    pointer: Res<'w, Pointer>,
    control: ResMut<'w, SimulationControl>,
    insets: ResMut<'w, ViewInsets>,
    state: ResMut<'w, PanelState>,
    time: Res<'w, Time<Real>>,
    keys: Res<'w, ButtonInput<KeyCode>>,
    gravity: Option<ResMut<'w, GravityParams>>,
    gravity_stats: Option<Res<'w, GravityStats>>,
    gravity_status: Option<Res<'w, crate::params::ParamsStatus<GravityParams>>>,
    bodies: Option<ResMut<'w, BodyView>>,
    liquid: ResMut<'w, LiquidStyle>,
    slot: Res<'w, SnapshotSlot>,
}

fn panel(
    mut contexts: EguiContexts,
    mut data: PanelData,
    mut resets: MessageWriter<ResetSimulation>,
    mut commands: Commands,
) -> Result {
    let ctx = contexts.ctx_mut()?;
    if data.keys.just_pressed(KeyCode::Tab) && !ctx.egui_wants_keyboard_input() {
        data.state.open = !data.state.open;
    }
    let dt = data.time.delta_secs();
    let stats = data.stats.clone();
    data.state.rates.update(dt, &stats);
    if !data.state.open {
        data.insets.set_if_neq(ViewInsets::default());
        return Ok(());
    }
    let mut root = egui::Ui::new(
        ctx.clone(),
        "sph_panel_root".into(),
        egui::UiBuilder::new()
            .layer_id(egui::LayerId::background())
            .max_rect(ctx.viewport_rect()),
    );
    let width = egui::Panel::left("sph_panel")
        .resizable(true)
        .default_size(300.0)
        .show(&mut root, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                // What the scene has comes first and open; the fluid's sections start folded
                // in a scene without fluid (the galaxy).
                let fluid = has_fluid(&data);
                controls_section(ui, &mut data, &mut resets, &mut commands);
                stats_section(ui, &data, &stats, fluid);
                if !fluid {
                    gravity_section(ui, &mut data);
                }
                scenario_section(ui, &mut data, &mut resets, fluid);
                fluid_section(ui, &mut data, fluid);
                if fluid {
                    gravity_section(ui, &mut data);
                }
                render_section(ui, &mut data, fluid);
                tools_section(ui, &mut data);
            });
        })
        .response
        .rect
        .width();
    data.insets.set_if_neq(ViewInsets {
        left: width,
        ..default()
    });
    Ok(())
}

fn controls_section(
    ui: &mut egui::Ui,
    data: &mut PanelData,
    resets: &mut MessageWriter<ResetSimulation>,
    commands: &mut Commands,
) {
    ui.heading("bevy_sph2d");
    ui.horizontal(|ui| {
        let label = if data.control.paused {
            "▶ Run"
        } else {
            "⏸ Pause"
        };
        if ui.button(label).on_hover_text("Space").clicked() {
            data.control.toggle_pause();
        }
        if ui
            .button("Step")
            .on_hover_text(". (one fixed tick)")
            .clicked()
        {
            data.control.step();
        }
        if ui.button("⟲ Reset").on_hover_text("R").clicked() {
            resets.write(ResetSimulation);
        }
        if ui
            .button("Save")
            .on_hover_text("F5: the fluid into the slot file")
            .clicked()
        {
            commands.queue(SaveSlot);
        }
        if ui
            .button("Load")
            .on_hover_text("F9: the fluid from the slot file")
            .clicked()
        {
            commands.queue(LoadSlot);
        }
    });
    match &data.slot.status {
        Some(Ok(message)) => {
            ui.small(message);
        }
        Some(Err(message)) => {
            ui.colored_label(egui::Color32::LIGHT_RED, message);
        }
        None => {}
    }
    ui.small("Mouse: left = tool, right = push, wheel = radius. Left/Right arrows tilt, Up levels, 1–5 tools, M the liquid poured, L liquid/particles, F5/F9 save/load, Tab hides the panel.");
}

/// Whether the scene has fluid: a scenario that spawns some, or particles.
fn has_fluid(data: &PanelData) -> bool {
    data.scenario.kind != ScenarioKind::Empty || data.stats.particles > 0
}

/// The clock's and the frame's statistics, and the fluid's where the scene has fluid.
fn stats_section(ui: &mut egui::Ui, data: &PanelData, stats: &SphStats, fluid: bool) {
    egui::CollapsingHeader::new("Statistics")
        .default_open(true)
        .show(ui, |ui| {
            let rates = data.state.rates;
            let ms_per_substep = if stats.substeps > 0 {
                stats.tick_ms / stats.substeps as f32
            } else {
                0.0
            };
            let mut rows = Vec::new();
            let mut row = |name: &'static str, value: String| rows.push((name, value));
            if !fluid {
                row("sim speed", format!("{:.2} × real time", rates.sim_speed));
                row("fps", format!("{:.0}", rates.fps));
                stat_grid(ui, "stats", rows);
                return;
            }
            row("particles", format!("{}", stats.particles));
            row("wall particles", format!("{}", stats.wall_particles));
            row("sub-steps / s", format!("{:.0}", rates.substeps_per_s));
            row("ms / sub-step", format!("{ms_per_substep:.2}"));
            row("ms / tick", format!("{:.1}", stats.tick_ms));
            row("sub-steps / tick", format!("{}", stats.substeps));
            row("sub-step dt", format!("{:.2e} s", stats.dt));
            row("sim speed", format!("{:.2} × real time", rates.sim_speed));
            row(
                "density error",
                format!(
                    "mean {:.2} %, max {:.1} %",
                    stats.mean_density_error, stats.max_density_error
                ),
            );
            row("max speed", format!("{:.2} m/s", stats.max_speed));
            if stats.solver == PressureSolver::Dfsph {
                let per_substep = |n: u32| n as f32 / stats.substeps.max(1) as f32;
                row(
                    "iterations / sub-step",
                    format!(
                        "density {:.1}, divergence {:.1}",
                        per_substep(stats.density_iterations),
                        per_substep(stats.divergence_iterations)
                    ),
                );
                row(
                    "solver density error",
                    format!("{:.3} %", stats.solver_density_error),
                );
            }
            row("sim time", format!("{:.2} s", stats.time));
            row("fps", format!("{:.0}", rates.fps));
            stat_grid(ui, "stats", rows);
            if stats.slow_motion {
                ui.colored_label(
                    egui::Color32::from_rgb(255, 190, 90),
                    "slow motion: the flow needs more sub-steps per tick than max sub-steps",
                );
            }
            if stats.non_finite_resets > 0 {
                ui.colored_label(
                    egui::Color32::LIGHT_RED,
                    format!("{} non-finite updates held back", stats.non_finite_resets),
                );
            }
            if stats.removed_non_finite + stats.removed_escaped > 0 {
                ui.colored_label(
                    egui::Color32::LIGHT_RED,
                    format!(
                        "removed: {} not finite, {} outside the tank",
                        stats.removed_non_finite, stats.removed_escaped
                    ),
                );
            }
        });
}

fn scenario_section(
    ui: &mut egui::Ui,
    data: &mut PanelData,
    resets: &mut MessageWriter<ResetSimulation>,
    fluid: bool,
) {
    egui::CollapsingHeader::new("Scenario")
        .default_open(fluid)
        .show(ui, |ui| {
            let mut scenario = *data.scenario;
            enum_combo(
                ui,
                "scenario",
                &mut scenario.kind,
                &ScenarioKind::ALL,
                |k| k.label(),
            );
            ui.add(
                egui::Slider::new(&mut scenario.particles, 200..=30_000)
                    .logarithmic(true)
                    .text("particles"),
            );
            let spacing = scenario.spacing(&SphScenario::tank(&data.params));
            ui.small(format!(
                "spacing {:.1} mm; applies on reset",
                1000.0 * spacing
            ));
            if scenario != *data.scenario {
                *data.scenario = scenario;
            }
            if ui.button("Start scenario").clicked() {
                resets.write(ResetSimulation);
            }
        });
}

fn fluid_section(ui: &mut egui::Ui, data: &mut PanelData, fluid: bool) {
    egui::CollapsingHeader::new("Fluid")
        .default_open(fluid)
        .show(ui, |ui| {
            let mut p = data.params.clone();
            fluid_presets(ui, &mut p, &mut data.liquid);
            fluid_material(ui, &mut p);
            fluid_liquids(ui, &mut p, &data.liquid);
            fluid_solver(ui, &mut p);
            ui.small(format!(
                "particle spacing Δx = {:.1} mm (set by the scenario's particle count)",
                1000.0 * p.particle_spacing
            ));
            if p != *data.params {
                *data.params = p;
            }
            if let Some(error) = &data.status.error {
                ui.colored_label(
                    egui::Color32::LIGHT_RED,
                    format!("refused: {error}; running on the last valid values"),
                );
            }
        });
}

/// Water, honey and gas: the preset's material, keeping the scene (spacing, kernel, gravity,
/// tank, solver) as it is.
fn fluid_presets(ui: &mut egui::Ui, p: &mut SphParams, liquid: &mut LiquidStyle) {
    ui.horizontal(|ui| {
        ui.label("preset");
        let keep = |preset: SphParams, current: &SphParams| SphParams {
            particle_spacing: current.particle_spacing,
            support_ratio: current.support_ratio,
            kernel: current.kernel,
            gravity: current.gravity,
            tank: current.tank,
            max_substeps: current.max_substeps,
            solver: current.solver,
            dfsph: current.dfsph,
            // A gas's rest density leaves no liquid within range of it.
            liquids: if preset.background_pressure > 0.0 {
                Vec::new()
            } else {
                current.liquids.clone()
            },
            speed_of_sound: if preset.background_pressure > 0.0 {
                preset.speed_of_sound
            } else {
                current.speed_of_sound
            },
            ..preset
        };
        if ui.button("Water").clicked() {
            *p = keep(SphParams::water(), p);
            *liquid = LiquidStyle::water();
        }
        if ui.button("Honey").clicked() {
            *p = keep(SphParams::honey(), p);
            *liquid = LiquidStyle::honey();
        }
        if ui.button("Gas").clicked() {
            *p = keep(SphParams::gas(), p);
        }
    });
}

/// The material and the scene: density, equation of state, viscosity, surface tension, kernel,
/// gravity, tank.
fn fluid_material(ui: &mut egui::Ui, p: &mut SphParams) {
    for row in [
        &SphParams::REST_DENSITY,
        &SphParams::SPEED_OF_SOUND,
        &SphParams::EOS_EXPONENT,
        &SphParams::BACKGROUND_PRESSURE,
        &SphParams::KINEMATIC_VISCOSITY,
        &SphParams::ARTIFICIAL_VISCOSITY,
        &SphParams::SURFACE_TENSION,
        &SphParams::CONTACT_ANGLE,
        &SphParams::SUPPORT_RATIO,
    ] {
        field_slider(ui, p, row);
    }
    enum_combo(
        ui,
        "kernel",
        &mut p.kernel,
        &KernelKind::ALL,
        KernelKind::label,
    );
    field_slider(ui, p, &SphParams::GRAVITY_X);
    field_slider(ui, p, &SphParams::GRAVITY_Y);
    if p.tank.is_some() {
        field_slider(ui, p, &SphParams::TANK_WIDTH);
        field_slider(ui, p, &SphParams::TANK_HEIGHT);
    }
}

/// The liquids besides the base one: each one's rest density and viscosity, and buttons that
/// add oil or brine and remove the last (removing one from the middle would change the others' materials).
fn fluid_liquids(ui: &mut egui::Ui, p: &mut SphParams, style: &LiquidStyle) {
    ui.label(format!(
        "liquids: base ({} kg/m³){}",
        p.rest_density,
        if p.liquids.is_empty() { ", alone" } else { "" }
    ));
    let (low, high) = (
        p.rest_density / MAX_DENSITY_RATIO,
        p.rest_density * MAX_DENSITY_RATIO,
    );
    for (k, liquid) in p.liquids.iter_mut().enumerate() {
        let color = style.liquid_color(k + 1, &liquid.name).to_srgba();
        let swatch = egui::Color32::from_rgb(
            (color.red * 255.0) as u8,
            (color.green * 255.0) as u8,
            (color.blue * 255.0) as u8,
        );
        ui.horizontal(|ui| {
            ui.colored_label(swatch, format!("{} {}", k + 1, liquid.name));
            param_slider(ui, &mut liquid.rest_density, low..=high, "", "kg/m³", false);
        });
        let row = &SphParams::KINEMATIC_VISCOSITY;
        let (least, most) = row.slider;
        let nu = &mut liquid.kinematic_viscosity;
        param_slider(ui, nu, least..=most, "   ν", row.unit, row.logarithmic);
    }
    ui.horizontal(|ui| {
        if ui.button("+ Oil").clicked() {
            p.liquids.push(Liquid::oil());
        }
        if ui.button("+ Brine").clicked() {
            p.liquids.push(Liquid::brine());
        }
        if !p.liquids.is_empty() && ui.button("Remove last").clicked() {
            p.liquids.pop();
        }
    });
}

/// The pressure solver and its settings, the sub-step budget and the walls' restitution.
fn fluid_solver(ui: &mut egui::Ui, p: &mut SphParams) {
    enum_combo(
        ui,
        "pressure solver",
        &mut p.solver,
        &PressureSolver::ALL,
        PressureSolver::label,
    );
    match p.solver {
        PressureSolver::Wcsph => field_slider(ui, p, &SphParams::CFL_NUMBER),
        PressureSolver::Dfsph => dfsph_settings(ui, p),
    }
    field_slider(ui, p, &SphParams::MAX_SUBSTEPS);
    field_slider(ui, p, &SphParams::WALL_RESTITUTION);
}

/// The slider of one row of `P`'s [`ParamTable::FIELDS`]: the label, unit, range and scale the
/// row gives.
fn field_slider<P: ParamTable>(ui: &mut egui::Ui, p: &mut P, row: &ParamField<P>) {
    let mut value = (row.get)(p);
    let (min, max) = row.slider_range(p);
    let mut slider = slider(&mut value, min..=max, row.label, row.unit, row.logarithmic);
    if row.integer {
        slider = slider.integer();
    }
    ui.add(slider);
    if value != (row.get)(p) {
        (row.set)(p, value);
    }
}

/// The divergence-free solver's settings.
fn dfsph_settings(ui: &mut egui::Ui, p: &mut SphParams) {
    for row in [
        &SphParams::DFSPH_CFL_NUMBER,
        &SphParams::DFSPH_MAX_TIME_STEP,
        &SphParams::DFSPH_DENSITY_TOLERANCE,
        &SphParams::DFSPH_DIVERGENCE_TOLERANCE,
        &SphParams::DFSPH_MAX_DENSITY_ITERATIONS,
        &SphParams::DFSPH_MAX_DIVERGENCE_ITERATIONS,
    ] {
        field_slider(ui, p, row);
    }
    ui.checkbox(&mut p.dfsph.warm_start, "warm start");
    ui.checkbox(
        &mut p.dfsph.fixed_budget,
        "fixed budget (no tolerance stop)",
    );
    ui.checkbox(&mut p.dfsph.grid_start, "start from a coarse-grid pressure");
}

fn gravity_section(ui: &mut egui::Ui, data: &mut PanelData) {
    let (Some(gravity), Some(stats)) = (data.gravity.as_mut(), data.gravity_stats.as_ref()) else {
        return;
    };
    egui::CollapsingHeader::new("Gravity (Barnes-Hut)")
        .default_open(true)
        .show(ui, |ui| {
            let mut g = (**gravity).clone();
            for row in GravityParams::FIELDS {
                field_slider(ui, &mut g, row);
            }
            enum_combo(
                ui,
                "far field",
                &mut g.multipole,
                &Multipole::ALL,
                Multipole::label,
            );
            ui.checkbox(&mut g.direct_sum, "exact direct sum (O(n²), for checking)");
            if g != **gravity {
                **gravity = g;
            }
            let mut rows = Vec::new();
            let mut row = |name: &'static str, value: String| rows.push((name, value));
            row("bodies", format!("{}", stats.bodies));
            row("tree nodes", format!("{}", stats.nodes));
            row("tree + field", format!("{:.1} ms", stats.field_ms));
            row("kinetic energy", format!("{:.4e} J", stats.kinetic_energy));
            row(
                "potential energy",
                format!("{:.4e} J", stats.potential_energy),
            );
            row("total energy", format!("{:.4e} J", stats.total_energy()));
            row(
                "momentum",
                format!(
                    "({:.3e}, {:.3e}) kg·m/s",
                    stats.momentum.x, stats.momentum.y
                ),
            );
            stat_grid(ui, "gravity_stats", rows);
            if let Some(error) = data.gravity_status.as_ref().and_then(|s| s.error.as_ref()) {
                ui.colored_label(egui::Color32::LIGHT_RED, format!("refused: {error}"));
            }
        });
}

/// How the fluid (in a scene with fluid) and the gravity bodies are drawn.
fn render_section(ui: &mut egui::Ui, data: &mut PanelData, fluid: bool) {
    egui::CollapsingHeader::new("Rendering")
        .default_open(true)
        .show(ui, |ui| {
            if fluid {
                let mut view = data.view.clone();
                enum_combo(ui, "draw", &mut view.draw, &ParticleDraw::ALL, |d| {
                    d.label()
                });
                enum_combo(ui, "colour by", &mut view.mode, &RenderMode::ALL, |m| {
                    m.label()
                });
                enum_combo(ui, "colour map", &mut view.color_map, &ColorMap::ALL, |m| {
                    m.label()
                });
                if view.mode != RenderMode::Solid {
                    ui.checkbox(&mut view.auto_range, "auto range");
                    ui.add_enabled_ui(!view.auto_range, |ui| {
                        ui.horizontal(|ui| {
                            ui.add(egui::DragValue::new(&mut view.range.min).speed(0.1));
                            ui.label("to");
                            ui.add(egui::DragValue::new(&mut view.range.max).speed(0.1));
                            ui.label(view.mode.unit());
                        });
                    });
                    color_bar(ui, view.color_map, view.range, view.mode.unit());
                }
                if view.draw == ParticleDraw::Liquid {
                    liquid_settings(ui, &mut data.liquid);
                } else {
                    param_slider(
                        ui,
                        &mut view.sprite_scale,
                        0.5..=4.0,
                        "sprite size",
                        "Δx",
                        false,
                    );
                }
                ui.checkbox(&mut view.interpolate, "interpolate between steps");
                ui.checkbox(&mut view.outline, "outline tank and solids");
                ui.checkbox(&mut view.fill_solids, "fill solids");
                if view != *data.view {
                    *data.view = view;
                }
            }
            if let Some(bodies) = data.bodies.as_mut() {
                ui.separator();
                ui.label("gravity bodies");
                let mut b = (**bodies).clone();
                enum_combo(
                    ui,
                    "colour bodies by",
                    &mut b.color_by,
                    &[BodyColor::Speed, BodyColor::Mass],
                    |c| match c {
                        BodyColor::Speed => "Speed",
                        BodyColor::Mass => "Mass",
                    },
                );
                enum_combo(
                    ui,
                    "body colour map",
                    &mut b.color_map,
                    &ColorMap::ALL,
                    |m| m.label(),
                );
                let unit = match b.color_by {
                    BodyColor::Speed => "m/s",
                    BodyColor::Mass => "kg",
                };
                color_bar(ui, b.color_map, b.range, unit);
                param_slider(ui, &mut b.size, 0.001..=0.2, "body size", "m", true);
                if b != **bodies {
                    **bodies = b;
                }
            }
        });
}

/// The liquid's look: shape, then colours.
fn liquid_settings(ui: &mut egui::Ui, style: &mut LiquidStyle) {
    let mut s = style.clone();
    ui.horizontal(|ui| {
        ui.label("look");
        if ui.button("Water").clicked() {
            s = LiquidStyle::water();
        }
        if ui.button("Honey").clicked() {
            s = LiquidStyle::honey();
        }
    });
    param_slider(
        ui,
        &mut s.threshold,
        0.05..=0.9,
        "surface threshold",
        "",
        false,
    );
    param_slider(
        ui,
        &mut s.splat_radius,
        1.0..=4.0,
        "splat radius",
        "Δx",
        false,
    );
    param_slider(
        ui,
        &mut s.resolution,
        0.25..=1.0,
        "field resolution",
        "× window",
        false,
    );
    param_slider(ui, &mut s.rim_width, 0.0..=3.0, "rim width", "Δx", false);
    param_slider(ui, &mut s.depth, 0.02..=1.0, "deep colour at", "m", true);
    param_slider(
        ui,
        &mut s.foam_speed,
        0.2..=10.0,
        "all foam at",
        "m/s",
        true,
    );
    for (label, color) in [
        ("shallow", &mut s.shallow_color),
        ("deep", &mut s.deep_color),
        ("rim", &mut s.rim_color),
        ("foam", &mut s.foam_color),
    ] {
        ui.horizontal(|ui| {
            let mut rgba = color.to_srgba().to_f32_array();
            if ui.color_edit_button_rgba_unmultiplied(&mut rgba).changed() {
                *color = Color::srgba(rgba[0], rgba[1], rgba[2], rgba[3]);
            }
            ui.label(label);
        });
    }
    if s != *style {
        *style = s;
    }
}

fn tools_section(ui: &mut egui::Ui, data: &mut PanelData) {
    egui::CollapsingHeader::new("Mouse tools")
        .default_open(true)
        .show(ui, |ui| {
            let mut tools = data.tools.clone();
            ui.horizontal_wrapped(|ui| {
                for tool in PointerTool::ALL {
                    ui.selectable_value(&mut tools.tool, tool, tool.label());
                }
            });
            param_slider(ui, &mut tools.radius, 0.01..=1.0, "radius", "m", true);
            param_slider(
                ui,
                &mut tools.strength,
                1.0..=500.0,
                "strength",
                "m/s²",
                true,
            );
            param_slider(
                ui,
                &mut tools.rate,
                0.5..=100.0,
                "drag / damping rate",
                "1/s",
                true,
            );
            param_slider(
                ui,
                &mut tools.pour_speed,
                0.1..=5.0,
                "pour speed",
                "m/s",
                false,
            );
            if !data.params.liquids.is_empty() {
                let name = |k: u8| match k.checked_sub(1) {
                    None => "base".to_string(),
                    Some(i) => data.params.liquids[i as usize].name.clone(),
                };
                egui::ComboBox::from_label("pours (M)")
                    .selected_text(name(tools.pour_material.0))
                    .show_ui(ui, |ui| {
                        for k in 0..=data.params.liquids.len() as u8 {
                            ui.selectable_value(
                                &mut tools.pour_material,
                                FluidMaterial(k),
                                name(k),
                            );
                        }
                    });
            }
            ui.label(format!("tilt {:.0}°", data.pointer.tilt.to_degrees()));
            if tools != *data.tools {
                *data.tools = tools;
            }
        });
}

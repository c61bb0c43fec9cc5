//! Small egui helpers of the panel.

use crate::render::{ColorMap, ColorRange};
use bevy_egui::egui;
use core::ops::RangeInclusive;

/// A labelled slider with a unit; logarithmic for quantities spanning decades.
pub(super) fn param_slider(
    ui: &mut egui::Ui,
    value: &mut f32,
    range: RangeInclusive<f32>,
    label: &str,
    unit: &str,
    logarithmic: bool,
) {
    ui.add(slider(value, range, label, unit, logarithmic));
}

/// The slider [`param_slider`] adds, for a caller to set more on (whole numbers, say).
pub(super) fn slider<'a>(
    value: &'a mut f32,
    range: RangeInclusive<f32>,
    label: &str,
    unit: &str,
    logarithmic: bool,
) -> egui::Slider<'a> {
    let text = if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} ({unit})")
    };
    egui::Slider::new(value, range)
        .logarithmic(logarithmic)
        // A value outside the slider (set by the game) stays as it is until dragged.
        .clamping(egui::SliderClamping::Edits)
        .text(text)
}

/// A combo box over `options`.
pub(super) fn enum_combo<T: Copy + PartialEq>(
    ui: &mut egui::Ui,
    label: &str,
    value: &mut T,
    options: &[T],
    name: impl Fn(T) -> &'static str,
) {
    egui::ComboBox::from_label(label)
        .selected_text(name(*value))
        .show_ui(ui, |ui| {
            for &option in options {
                ui.selectable_value(value, option, name(option));
            }
        });
}

/// A two-column grid of statistics: names, and values in a monospace font.
pub(super) fn stat_grid(ui: &mut egui::Ui, id: &str, rows: Vec<(&'static str, String)>) {
    egui::Grid::new(id).num_columns(2).show(ui, |ui| {
        for (name, value) in rows {
            ui.label(name);
            ui.monospace(value);
            ui.end_row();
        }
    });
}

/// The colour bar of `map` over `range`, with its end values.
pub(super) fn color_bar(ui: &mut egui::Ui, map: ColorMap, range: ColorRange, unit: &str) {
    let width = ui.available_width().min(260.0);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 14.0), egui::Sense::hover());
    let steps = 64;
    for i in 0..steps {
        let t = (i as f32 + 0.5) / steps as f32;
        let c = map.sample(t).to_srgba();
        let color = egui::Color32::from_rgb(
            (c.red * 255.0) as u8,
            (c.green * 255.0) as u8,
            (c.blue * 255.0) as u8,
        );
        let x0 = rect.left() + rect.width() * i as f32 / steps as f32;
        let x1 = rect.left() + rect.width() * (i + 1) as f32 / steps as f32;
        let cell = egui::Rect::from_min_max(
            egui::pos2(x0, rect.top()),
            egui::pos2(x1 + 0.5, rect.bottom()),
        );
        ui.painter().rect_filled(cell, 0.0, color);
    }
    ui.horizontal(|ui| {
        ui.small(format!("{} {unit}", significant(range.min)));
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            ui.small(format!("{} {unit}", significant(range.max)));
        });
    });
}

/// `value` with about four significant digits (no exponent for everyday magnitudes).
fn significant(value: f32) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let magnitude = value.abs().log10().floor() as i32;
    if !(-4..=6).contains(&magnitude) {
        return format!("{value:.3e}");
    }
    let decimals = (3 - magnitude).clamp(0, 7) as usize;
    format!("{value:.decimals$}")
}

#[cfg(test)]
mod tests {
    use super::significant;

    #[test]
    fn four_significant_digits() {
        assert_eq!(significant(998.123_4), "998.1");
        assert_eq!(significant(0.012_341), "0.01234");
        assert_eq!(significant(12.0), "12.00");
        assert_eq!(significant(1.5e9), "1.500e9");
        assert_eq!(significant(0.0), "0");
    }
}

//! The editor's colours where they differ from egui's defaults, and who paints the window's
//! background.
//!
//! egui shades every pixel it paints with its own shader (a texture sample, gamma conversions
//! and blending); on a CPU rasterizer one full-window fill at 1600×1000 costs about as much as
//! the whole 3D viewport (docs/rendering.md, "What a frame draws"). The panels' background is
//! one flat colour under everything, so the window's clear colour paints it (a clear is a fill
//! of memory, not a shaded pass) and egui's panels are given a transparent fill. Where nobody
//! clears the window with that colour (the UI tests' harness), [`crate::app::EditorApp`]
//! paints it as one rectangle instead, so the picture is the same either way.

use egui::{Color32, Context, Theme, Visuals};

/// The panels' background colour for `visuals`' theme: egui's own panel fill.
#[must_use]
pub fn panel_background(visuals: &Visuals) -> Color32 {
    if visuals.dark_mode {
        Visuals::dark().panel_fill
    } else {
        Visuals::light().panel_fill
    }
}

/// Gives egui's panels (side, top, bottom and central) a transparent fill in both themes; the
/// background under them is [`panel_background`], painted by whoever draws the window.
pub fn install(ctx: &Context) {
    for theme in [Theme::Dark, Theme::Light] {
        ctx.style_mut_of(theme, |style| style.visuals.panel_fill = Color32::TRANSPARENT);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_are_transparent_and_the_background_is_egui_s_panel_fill() {
        let ctx = Context::default();
        install(&ctx);
        for (theme, visuals) in [(Theme::Dark, Visuals::dark()), (Theme::Light, Visuals::light())] {
            ctx.set_theme(theme);
            let style = ctx.global_style();
            assert_eq!(style.visuals.panel_fill, Color32::TRANSPARENT);
            assert_eq!(panel_background(&style.visuals), visuals.panel_fill);
            assert_ne!(visuals.panel_fill, Color32::TRANSPARENT);
        }
    }
}

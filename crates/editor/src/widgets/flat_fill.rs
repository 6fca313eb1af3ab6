//! Opaque rectangles of one colour, filled by a paint callback of the GPU viewport's
//! ([`crate::gpu_view::FlatFill`]) where the window is drawn with wgpu, by egui's painter
//! elsewhere. On a CPU rasterizer egui's textured-mesh shader costs about 15 ns for every pixel
//! it paints; a fill with the blend constant and no texture a fraction of that, which matters
//! for the large backgrounds (the dope sheet's and the curve view's) that are redrawn every
//! frame (docs/rendering.md, "What a frame draws").

use egui::{Color32, Painter, Rect};

/// Fills `rect` (within the painter's clip) with the opaque `colour`; `gpu` when the window is
/// drawn with wgpu and the fill pipeline is installed ([`crate::context::FrameCtx::gpu_fills`]).
/// A translucent colour is left to egui, which blends it.
pub fn fill(painter: &Painter, rect: Rect, colour: Color32, gpu: bool) {
    if gpu && colour.is_opaque() {
        let clipped = rect.intersect(painter.clip_rect());
        if clipped.is_positive() {
            painter.add(egui_wgpu::Callback::new_paint_callback(clipped, crate::gpu_view::FlatFill(colour)));
        }
    } else {
        painter.rect_filled(rect, 0.0, colour);
    }
}

/// `src` painted over the opaque `dst` as egui blends (premultiplied alpha, on the stored
/// gamma-encoded values): the opaque colour a translucent shade gives over a known background.
#[must_use]
pub fn over(dst: Color32, src: Color32) -> Color32 {
    let keep = 255 - u16::from(src.a());
    let channel = |s: u8, d: u8| (u16::from(s) + (u16::from(d) * keep + 127) / 255).min(255) as u8;
    Color32::from_rgb(channel(src.r(), dst.r()), channel(src.g(), dst.g()), channel(src.b(), dst.b()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shapes one frame paints with `fill(…, colour, gpu)` over a 100 × 50 rect.
    fn shapes(colour: Color32, gpu: bool) -> Vec<egui::Shape> {
        let ctx = egui::Context::default();
        let output = ctx.run_ui(egui::RawInput::default(), |ui| {
            let rect = Rect::from_min_size(egui::pos2(10.0, 20.0), egui::vec2(100.0, 50.0));
            fill(ui.painter(), rect, colour, gpu);
        });
        output.shapes.into_iter().map(|clipped| clipped.shape).collect()
    }

    #[test]
    fn over_composites_premultiplied_colours() {
        let bg = Color32::from_gray(10);
        assert_eq!(over(bg, Color32::TRANSPARENT), bg);
        assert_eq!(over(bg, Color32::from_rgb(200, 100, 50)), Color32::from_rgb(200, 100, 50));
        // Half-transparent white (premultiplied 128, alpha 128) over grey 10: 128 + 10 · 127/255.
        let half_white = Color32::from_white_alpha(128);
        assert_eq!(over(bg, half_white), Color32::from_gray(133));
        // egui's own gamma_multiply keeps colours premultiplied.
        let shade = Color32::from_gray(60).gamma_multiply(0.5);
        assert_eq!(over(bg, shade), Color32::from_gray(30 + 5));
    }

    #[test]
    fn opaque_fills_go_to_the_gpu_callback_and_everything_else_to_egui() {
        let grey = Color32::from_gray(10);
        let [gpu] = shapes(grey, true).try_into().expect("one shape");
        let egui::Shape::Callback(callback) = gpu else { panic!("{gpu:?}") };
        assert_eq!(callback.rect, Rect::from_min_size(egui::pos2(10.0, 20.0), egui::vec2(100.0, 50.0)));
        assert!(callback.callback.downcast_ref::<egui_wgpu::Callback>().is_some(), "an egui-wgpu callback");
        for (colour, gpu) in [(grey, false), (Color32::from_black_alpha(100), true)] {
            let [shape] = shapes(colour, gpu).try_into().expect("one shape");
            assert!(matches!(&shape, egui::Shape::Rect(r) if r.fill == colour), "{shape:?}");
        }
    }
}

//! File ▸ Render animation: the size, the frame range, the movie type, motion blur and the
//! output file of a playblast; while it renders (on its own thread, [`crate::render_job`]), a
//! progress bar with the time left and a Cancel button. The viewport stays usable meanwhile.

use std::path::{Path, PathBuf};

use egui::Context;

use crate::actions::{Action, Actions, ViewChange};
use crate::context::FrameCtx;
use crate::playblast::{MotionBlur, MovieFormat, Playblast, SceneSound, DEFAULT_SHUTTER};
use crate::view::LookThrough;

/// The dialog's fields, kept while the editor runs.
pub struct RenderDialog {
    width: u32,
    height: u32,
    first: i64,
    last: i64,
    format: MovieFormat,
    motion_blur: bool,
    samples: u32,
    shutter: f64,
    output: String,
    /// The camera each frame is seen through (`None`: the viewport's view), as
    /// `keyrig render`'s `--camera`/`--view`.
    through: Option<LookThrough>,
    /// The document (path) the range and the output were filled for.
    filled_for: Option<Option<PathBuf>>,
}

impl Default for RenderDialog {
    fn default() -> Self {
        RenderDialog {
            width: 1280,
            height: 720,
            first: 0,
            last: 0,
            format: MovieFormat::Mp4,
            motion_blur: false,
            samples: 8,
            shutter: DEFAULT_SHUTTER,
            output: String::new(),
            through: None,
            filled_for: None,
        }
    }
}

impl RenderDialog {
    /// The dialog, when File ▸ Render animation opened it.
    pub fn ui(&mut self, ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
        if !frame.view.show_render {
            return;
        }
        let scene_path = frame.doc.path().map(Path::to_path_buf);
        if self.filled_for.as_ref() != Some(&scene_path) {
            self.fill_for(frame, scene_path.as_deref());
            self.filled_for = Some(scene_path);
        }
        let mut open = true;
        egui::Window::new("Render animation")
            .open(&mut open)
            .resizable(false)
            .collapsible(false)
            .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
            .show(ctx, |ui| {
                let running = frame.render.is_some();
                ui.add_enabled_ui(!running, |ui| self.fields_ui(ui, frame));
                ui.separator();
                match frame.render {
                    Some(job) => progress_ui(ui, job, actions),
                    None => {
                        if ui
                            .button("Render")
                            .on_hover_text("Render the frames and write the movie")
                            .clicked()
                        {
                            match self.playblast(frame) {
                                Ok(blast) => {
                                    actions.push(Action::StartRender { blast, through: self.through });
                                }
                                Err(e) => actions.push(Action::Error(e)),
                            }
                        }
                    }
                }
            });
        if !open {
            actions.view(ViewChange::ShowRender(false));
        }
    }

    /// The range and render size of the scene, the camera `keyrig render` would use (the one
    /// the viewport looks through, else the active camera, else the view), and an output beside
    /// the scene file named after it.
    fn fill_for(&mut self, frame: &FrameCtx<'_>, scene_path: Option<&Path>) {
        let scene = frame.scene();
        let range = scene.frame_range;
        (self.first, self.last) = (i64::from(range.start), i64::from(range.end));
        (self.width, self.height) = scene.render_size.map_or((1280, 720), |s| (s.width, s.height));
        self.through = frame.view.look_through.or((!scene.cameras.is_empty()).then_some(LookThrough::Active));
        let stem = scene_path
            .and_then(Path::file_stem)
            .map_or_else(|| "playblast".to_owned(), |s| s.to_string_lossy().into_owned());
        let folder = scene_path.and_then(Path::parent).map(Path::to_path_buf).unwrap_or_default();
        self.output = folder.join(self.output_name(&stem)).display().to_string();
    }

    fn output_name(&self, stem: &str) -> String {
        match self.format {
            MovieFormat::PngFrames => format!("{stem}_frames/frame_####.png"),
            format => format!("{stem}.{}", format.extension()),
        }
    }

    fn fields_ui(&mut self, ui: &mut egui::Ui, frame: &FrameCtx<'_>) {
        egui::Grid::new("render_fields").num_columns(2).spacing([12.0, 6.0]).show(ui, |ui| {
            let range = frame.scene().frame_range;
            let (start, end) = (i64::from(range.start), i64::from(range.end));
            labelled(ui, "Width", |ui| {
                ui.add(egui::DragValue::new(&mut self.width).range(2..=8192).suffix(" px"))
            });
            labelled(ui, "Height", |ui| {
                ui.add(egui::DragValue::new(&mut self.height).range(2..=8192).suffix(" px"))
            });
            labelled(ui, "Camera", |ui| {
                let scene = frame.scene();
                let name = |t: Option<LookThrough>| match t {
                    None => "The viewport's view".to_owned(),
                    Some(LookThrough::Active) => "Active camera (markers cut)".to_owned(),
                    Some(LookThrough::Camera(c)) => {
                        scene.cameras.get(c).map_or_else(String::new, |c| c.name.clone())
                    }
                };
                egui::ComboBox::from_id_salt("render_camera")
                    .selected_text(name(self.through))
                    .show_ui(ui, |ui| {
                        let mut choices = vec![None];
                        if !scene.cameras.is_empty() {
                            choices.push(Some(LookThrough::Active));
                        }
                        choices.extend((0..scene.cameras.len()).map(|c| Some(LookThrough::Camera(c))));
                        for choice in choices {
                            ui.selectable_value(&mut self.through, choice, name(choice));
                        }
                    })
                    .response
                    .on_hover_text("What each frame is seen through, as keyrig render's --camera and --view")
            });
            labelled(ui, "First frame", |ui| {
                ui.add(egui::DragValue::new(&mut self.first).range(start..=end))
            });
            labelled(ui, "Last frame", |ui| ui.add(egui::DragValue::new(&mut self.last).range(start..=end)));

            let before = self.format;
            labelled(ui, "Format", |ui| {
                egui::ComboBox::from_id_salt("render_format")
                    .selected_text(self.format.label())
                    .show_ui(ui, |ui| {
                        for format in MovieFormat::ALL {
                            ui.selectable_value(&mut self.format, format, format.label());
                        }
                    })
                    .response
            });
            if self.format != before {
                self.output = retarget(&self.output, before, self.format);
            }

            ui.label("");
            ui.checkbox(&mut self.motion_blur, "Motion blur");
            ui.end_row();
            let blur = self.motion_blur;
            labelled(ui, "Samples", |ui| {
                ui.add_enabled(blur, egui::DragValue::new(&mut self.samples).range(2..=64))
                    .on_hover_text("Renders averaged into each frame")
            });
            labelled(ui, "Shutter", |ui| {
                ui.add_enabled(blur, egui::Slider::new(&mut self.shutter, 0.0..=1.0)).on_hover_text(
                    "The fraction of the frame interval the shutter is open, centred on the frame",
                )
            });

            labelled(ui, "Output", |ui| {
                ui.add(egui::TextEdit::singleline(&mut self.output).desired_width(320.0))
            });
        });
        ui.label(
            egui::RichText::new(format!(
                "{} frames at {} fps, as keyrig render renders them",
                (self.last - self.first + 1).max(0),
                frame.scene().fps
            ))
            .weak(),
        );
    }

    /// The playblast the fields describe.
    fn playblast(&self, frame: &FrameCtx<'_>) -> Result<Playblast, String> {
        if self.output.trim().is_empty() {
            return Err("Render animation: choose an output file".into());
        }
        let blast = Playblast {
            first: self.first,
            last: self.last,
            fps: frame.scene().fps,
            size: (self.width, self.height),
            format: self.format,
            output: PathBuf::from(self.output.trim()),
            motion_blur: if self.motion_blur {
                MotionBlur { samples: self.samples, shutter: self.shutter }
            } else {
                MotionBlur::OFF
            },
            sound: SceneSound {
                clips: frame.scene().sounds.clone(),
                base_dir: frame.base_dir().map(Path::to_path_buf),
            },
        };
        blast.validate().map_err(|e| format!("Render animation: {e}"))?;
        Ok(blast)
    }
}

/// A grid row: `label`, then the widget `add` makes, named by the label for screen readers.
fn labelled(ui: &mut egui::Ui, label: &str, add: impl FnOnce(&mut egui::Ui) -> egui::Response) {
    let label = ui.label(label);
    add(ui).labelled_by(label.id);
    ui.end_row();
}

/// The output path for another format: the extension swapped (numbered PNGs get a pattern).
fn retarget(output: &str, from: MovieFormat, to: MovieFormat) -> String {
    let path = Path::new(output);
    let (folder, stem) = match from {
        MovieFormat::PngFrames => {
            let folder = path.parent().unwrap_or(Path::new(""));
            let stem = folder
                .file_name()
                .map(|n| n.to_string_lossy().trim_end_matches("_frames").to_owned())
                .unwrap_or_else(|| "playblast".into());
            (folder.parent().unwrap_or(Path::new("")).to_path_buf(), stem)
        }
        _ => (
            path.parent().unwrap_or(Path::new("")).to_path_buf(),
            path.file_stem().map_or_else(|| "playblast".into(), |s| s.to_string_lossy().into_owned()),
        ),
    };
    let name = match to {
        MovieFormat::PngFrames => format!("{stem}_frames/frame_####.png"),
        format => format!("{stem}.{}", format.extension()),
    };
    folder.join(name).display().to_string()
}

/// The running render's bar, time left and Cancel button.
fn progress_ui(ui: &mut egui::Ui, job: &crate::render_job::RenderJob, actions: &mut Actions) {
    let total = job.blast.frame_count();
    let (fraction, text) = match job.progress() {
        Some(p) => {
            let left = p
                .remaining()
                .map_or_else(String::new, |d| format!(", {} left", seconds_text(d.as_secs_f64())));
            (p.fraction(), format!("frame {} of {total}{left}", p.done))
        }
        None => (0.0, format!("starting ({total} frames)")),
    };
    ui.add(egui::ProgressBar::new(fraction).text(text).desired_width(360.0));
    ui.horizontal(|ui| {
        if job.is_cancelling() {
            ui.label("Cancelling…");
        } else if ui.button("Cancel").on_hover_text("Stop rendering; the movie is not written").clicked() {
            actions.push(Action::CancelRender);
        }
    });
}

/// `75 s` → "1 min 15 s".
fn seconds_text(seconds: f64) -> String {
    let s = seconds.round() as u64;
    if s >= 60 {
        format!("{} min {} s", s / 60, s % 60)
    } else {
        format!("{s} s")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn changing_the_format_keeps_the_name() {
        let to_gif = retarget("/shots/arm.mp4", MovieFormat::Mp4, MovieFormat::Gif);
        assert_eq!(to_gif, "/shots/arm.gif");
        let to_frames = retarget(&to_gif, MovieFormat::Gif, MovieFormat::PngFrames);
        assert_eq!(to_frames, "/shots/arm_frames/frame_####.png");
        assert_eq!(retarget(&to_frames, MovieFormat::PngFrames, MovieFormat::Apng), "/shots/arm.png");
        assert_eq!(seconds_text(75.2), "1 min 15 s");
        assert_eq!(seconds_text(9.6), "10 s");
    }
}

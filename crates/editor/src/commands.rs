//! Every user action of the editor, with its label, tooltip and keyboard shortcuts. The one
//! list drives the menus, the toolbar tooltips, the shortcut handler and the help window.

use egui::{Key, KeyboardShortcut, Modifiers};
use keyrig_core::DeformerKind;

/// A user action.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    New,
    Open,
    Save,
    SaveAs,
    Import,
    ImportSound,
    ExportGltf,
    RenderAnimation,
    Quit,
    Undo,
    Redo,
    ToggleRecord,
    ToggleIk,
    InsertKey,
    Delete,
    DuplicateItem,
    RenameItem,
    CopyKeys,
    PasteKeys,
    CopyPose,
    PastePose,
    PastePoseMirrored,
    PlayPause,
    ToggleLoop,
    NextFrame,
    PrevFrame,
    FirstFrame,
    LastFrame,
    PrevKey,
    NextKey,
    ToggleGrid,
    ToggleBones,
    ToggleOnionSkin,
    SetDeformer(DeformerKind),
    CameraFront,
    CameraSide,
    CameraTop,
    CameraShoulder,
    CameraElbow,
    FrameSelection,
    LookThroughCamera,
    CameraToView,
    AddCamera,
    ToggleMarker,
    BindCameraToMarker,
    HideSelected,
    ShowHidden,
    TogglePreviewRange,
    GizmoMove,
    GizmoTurn,
    GizmoScale,
    UndoHistory,
    ReduceKeys,
    SmoothKeys,
    Retarget,
    ShowHelp,
}

const fn sc(modifiers: Modifiers, key: Key) -> KeyboardShortcut {
    KeyboardShortcut::new(modifiers, key)
}

const NONE: Modifiers = Modifiers::NONE;
const CMD: Modifiers = Modifiers::COMMAND;
const CMD_SHIFT: Modifiers = Modifiers::COMMAND.plus(Modifiers::SHIFT);

impl Command {
    /// All commands, in the order the help window lists them. Commands that share a shortcut
    /// key with fewer modifiers come after the ones with more (Ctrl+Shift+Z before Ctrl+Z), so
    /// the shortcut handler tries the most specific first.
    pub const ALL: [Command; 59] = [
        Command::New,
        Command::Open,
        Command::SaveAs,
        Command::Save,
        Command::ImportSound,
        Command::Import,
        Command::ExportGltf,
        Command::RenderAnimation,
        Command::Quit,
        // Ctrl+Alt+Z before Ctrl+Z (Undo), which would take it too.
        Command::UndoHistory,
        Command::Redo,
        Command::Undo,
        Command::ToggleRecord,
        Command::ToggleIk,
        Command::InsertKey,
        Command::Delete,
        Command::DuplicateItem,
        // Before Rename (Ctrl+R), which its Ctrl+Alt+R contains.
        Command::Retarget,
        Command::RenameItem,
        Command::CopyKeys,
        Command::PasteKeys,
        Command::CopyPose,
        Command::PastePoseMirrored,
        Command::PastePose,
        // Ctrl+Alt+P before Ctrl+P (Play / pause), which would take it too.
        Command::TogglePreviewRange,
        Command::PlayPause,
        Command::ToggleLoop,
        Command::NextFrame,
        Command::PrevFrame,
        Command::FirstFrame,
        Command::LastFrame,
        Command::PrevKey,
        Command::NextKey,
        Command::ToggleGrid,
        Command::ToggleBones,
        Command::ToggleOnionSkin,
        Command::GizmoMove,
        Command::GizmoTurn,
        Command::GizmoScale,
        Command::SetDeformer(DeformerKind::Rigid),
        Command::SetDeformer(DeformerKind::LinearBlend),
        Command::SetDeformer(DeformerKind::BonesBlending),
        Command::SetDeformer(DeformerKind::DualQuaternion),
        Command::CameraFront,
        Command::CameraSide,
        Command::CameraTop,
        Command::CameraShoulder,
        Command::CameraElbow,
        Command::FrameSelection,
        Command::CameraToView,
        Command::LookThroughCamera,
        Command::AddCamera,
        Command::ToggleMarker,
        Command::BindCameraToMarker,
        Command::ShowHidden,
        Command::HideSelected,
        Command::ReduceKeys,
        Command::SmoothKeys,
        Command::ShowHelp,
    ];

    /// Text for menus and the help window.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Command::New => "New",
            Command::Open => "Open…",
            Command::Save => "Save",
            Command::SaveAs => "Save as…",
            Command::Import => "Import…",
            Command::ImportSound => "Import sound…",
            Command::ExportGltf => "Export…",
            Command::RenderAnimation => "Render animation…",
            Command::Quit => "Quit",
            Command::Undo => "Undo",
            Command::Redo => "Redo",
            Command::ToggleRecord => "Record mode",
            Command::ToggleIk => "IK posing",
            Command::InsertKey => "Insert key",
            Command::Delete => "Delete",
            Command::DuplicateItem => "Duplicate",
            Command::RenameItem => "Rename…",
            Command::CopyKeys => "Copy keys",
            Command::PasteKeys => "Paste keys",
            Command::CopyPose => "Copy pose",
            Command::PastePose => "Paste pose",
            Command::PastePoseMirrored => "Paste pose mirrored",
            Command::PlayPause => "Play / pause",
            Command::ToggleLoop => "Loop",
            Command::NextFrame => "Next frame",
            Command::PrevFrame => "Previous frame",
            Command::FirstFrame => "First frame",
            Command::LastFrame => "Last frame",
            Command::PrevKey => "Previous key",
            Command::NextKey => "Next key",
            Command::ToggleGrid => "Grid",
            Command::ToggleBones => "Bones",
            Command::ToggleOnionSkin => "Onion skin",
            Command::SetDeformer(k) => k.label(),
            Command::CameraFront => "Front view",
            Command::CameraSide => "Side view",
            Command::CameraTop => "Top view",
            Command::CameraShoulder => "Shoulder view",
            Command::CameraElbow => "Elbow view",
            Command::FrameSelection => "Frame selection",
            Command::LookThroughCamera => "Look through camera",
            Command::CameraToView => "Set camera to view",
            Command::AddCamera => "Add camera",
            Command::ToggleMarker => "Add or remove marker",
            Command::BindCameraToMarker => "Bind camera to marker",
            Command::HideSelected => "Hide selected",
            Command::ShowHidden => "Show hidden",
            Command::TogglePreviewRange => "Preview range",
            Command::GizmoMove => "Move gizmo",
            Command::GizmoTurn => "Turn gizmo",
            Command::GizmoScale => "Scale gizmo",
            Command::UndoHistory => "Undo history",
            Command::ReduceKeys => "Reduce keys…",
            Command::SmoothKeys => "Smooth keys…",
            Command::Retarget => "Retarget…",
            Command::ShowHelp => "Keyboard shortcuts",
        }
    }

    /// One sentence saying what the command does.
    #[must_use]
    pub fn tooltip(self) -> &'static str {
        match self {
            Command::New => "Start a new, empty scene",
            Command::Open => "Open a scene file (.ron)",
            Command::Save => "Save the scene to its file",
            Command::SaveAs => "Save the scene to a new file",
            Command::Import => {
                "Import a model (glTF, MD2, VRML, X3D, Inventor) or a sound (WAV, FLAC, MP3, Ogg) into the scene"
            }
            Command::ImportSound => "Add a sound clip (WAV, FLAC, MP3, Ogg) at the current frame",
            Command::ExportGltf => "Export the scene's meshes, skins and animation as glTF",
            Command::RenderAnimation => "Render frames as a movie (MP4, GIF, animated PNG) or PNG files",
            Command::Quit => "Close the editor (asks before losing changes)",
            Command::Undo => "Revert the last edit",
            Command::Redo => "Repeat the last undone edit",
            Command::ToggleRecord => {
                "Auto-key: a gizmo or inspector change writes a key at the current frame"
            }
            Command::ToggleIk => {
                "Drag a handle at the selected joint (a hand): the chain above it follows (two bones \
                 by default; the inspector sets the length)"
            }
            Command::InsertKey => {
                "Key the selection's current pose at the current frame (in IK posing, with the joints \
                 of the selected joint's chain)"
            }
            Command::Delete => "Delete the selected keys; with no key selected, the selected object or light",
            Command::DuplicateItem => {
                "Copy the selected object, light or camera, keys included, select the copy and move it with the pointer (click or Enter places it, Escape leaves it on the original)"
            }
            Command::RenameItem => {
                "Rename the selected object, joint or light (or double-click it in the outliner)"
            }
            Command::CopyKeys => "Copy the selected keys",
            Command::PasteKeys => "Paste copied keys at the current frame",
            Command::CopyPose => "Copy the values of the selected joints and objects at the current frame",
            Command::PastePose => "Apply the copied pose at the current frame (keys it in record mode)",
            Command::PastePoseMirrored => {
                "Apply the copied pose to the other side (.L/.R, Left/Right), mirrored across the character's fitted symmetry plane"
            }
            Command::PlayPause => "Start or stop playback",
            Command::ToggleLoop => "Loop playback over the frame range",
            Command::NextFrame => "Step one frame forward",
            Command::PrevFrame => "Step one frame back",
            Command::FirstFrame => "Go to the first frame of the range",
            Command::LastFrame => "Go to the last frame of the range",
            Command::PrevKey => {
                "Go to the previous key of the selection (of the scene when nothing is selected)"
            }
            Command::NextKey => "Go to the next key of the selection (of the scene when nothing is selected)",
            Command::ToggleGrid => "Show or hide the ground grid",
            Command::ToggleBones => "Show or hide the skeleton's bones",
            Command::ToggleOnionSkin => "Ghosts of the selection before (warm) and after (cool) the frame",
            Command::SetDeformer(DeformerKind::Rigid) => "Skin each vertex to one bone (v' = M(j)·v)",
            Command::SetDeformer(DeformerKind::LinearBlend) => {
                "Linear blend skinning; collapses under twist (candy wrapper)"
            }
            Command::SetDeformer(DeformerKind::BonesBlending) => {
                "Kavan & Žára bones blending: keeps the cross-section under twist"
            }
            Command::SetDeformer(DeformerKind::DualQuaternion) => {
                "Dual quaternion skinning: preserves volume"
            }
            Command::CameraFront => "Look along −Z at the scene",
            Command::CameraSide => "Look along −X at the scene",
            Command::CameraTop => "Look down at the scene",
            Command::CameraShoulder => "Look down the arm at the first joint",
            Command::CameraElbow => "Look down the arm at the second joint",
            Command::FrameSelection => "Centre the view on the selected joint, object or light",
            Command::LookThroughCamera => {
                "View through the selected (else the active) camera; again, or orbit, to leave"
            }
            Command::CameraToView => {
                "Move the selected (else the active) camera to the view; keys in record mode"
            }
            Command::AddCamera => "Add a scene camera where the view is, looking as it looks",
            Command::ToggleMarker => "Add a timeline marker at the current frame, or remove the one there",
            Command::BindCameraToMarker => {
                "Make the selected camera the active one from this frame on (a marker)"
            }
            Command::HideSelected => {
                "Hide the selected objects in the viewport (not in renders; the outliner still lists them)"
            }
            Command::ShowHidden => "Show every object hidden in the viewport again",
            Command::TogglePreviewRange => {
                "Loop playback over part of the range (the selected keys' frames, else from here to the end), or the whole range again"
            }
            Command::GizmoMove => "The gizmo shows only its move arrows and planes; again: move and turn",
            Command::GizmoTurn => "The gizmo shows only its rotation rings; again: move and turn",
            Command::GizmoScale => {
                "Scale handles for the selected objects instead of move and turn; again: move and turn"
            }
            Command::UndoHistory => "List the undo steps; a click on one goes back (or forward) to it",
            Command::ReduceKeys => {
                "Keep as few keys as hold the curves within an angle and a distance of what they are (the selected keys' channels, else the selected object's, else the scene's)"
            }
            Command::Retarget => {
                "Put the action a skeleton in another file plays (a BVH take, a glTF or FBX character) onto the selected character as a new action"
            }
            Command::SmoothKeys => {
                "Filter out motion faster than a cutoff in Hz (Butterworth, no lag) from the selected keys' channels, else the selected object's, else the scene's"
            }
            Command::ShowHelp => "List every command and its shortcut",
        }
    }

    /// The keyboard shortcuts that run the command (the first is shown in menus).
    #[must_use]
    pub fn shortcuts(self) -> Vec<KeyboardShortcut> {
        match self {
            Command::New => vec![sc(CMD, Key::N)],
            Command::Open => vec![sc(CMD, Key::O)],
            Command::Save => vec![sc(CMD, Key::S)],
            Command::SaveAs => vec![sc(CMD_SHIFT, Key::S)],
            Command::Import => vec![sc(CMD, Key::I)],
            Command::ImportSound => vec![sc(CMD_SHIFT, Key::I)],
            Command::ExportGltf => vec![sc(CMD, Key::E)],
            Command::RenderAnimation => vec![sc(CMD_SHIFT, Key::R)],
            Command::Quit => vec![sc(CMD, Key::Q)],
            Command::Undo => vec![sc(CMD, Key::Z)],
            Command::Redo => vec![sc(CMD_SHIFT, Key::Z), sc(CMD, Key::Y)],
            Command::ToggleRecord => vec![sc(NONE, Key::R)],
            Command::ToggleIk => vec![sc(Modifiers::SHIFT, Key::I)],
            Command::InsertKey => vec![sc(NONE, Key::I)],
            Command::Delete => vec![sc(NONE, Key::Delete), sc(NONE, Key::Backspace)],
            Command::DuplicateItem => vec![sc(Modifiers::SHIFT, Key::D)],
            Command::RenameItem => vec![sc(CMD, Key::R)],
            Command::CopyKeys => vec![sc(CMD, Key::C)],
            Command::PasteKeys => vec![sc(CMD, Key::V)],
            Command::CopyPose => vec![sc(Modifiers::ALT, Key::C)],
            Command::PastePose => vec![sc(Modifiers::ALT, Key::V)],
            Command::PastePoseMirrored => vec![sc(Modifiers::ALT.plus(Modifiers::SHIFT), Key::V)],
            Command::PlayPause => vec![sc(CMD, Key::P), sc(NONE, Key::Space)],
            Command::ToggleLoop => vec![sc(NONE, Key::L)],
            Command::NextFrame => vec![sc(NONE, Key::ArrowRight)],
            Command::PrevFrame => vec![sc(NONE, Key::ArrowLeft)],
            Command::FirstFrame => vec![sc(NONE, Key::Home)],
            Command::LastFrame => vec![sc(NONE, Key::End)],
            Command::PrevKey => vec![sc(NONE, Key::ArrowDown)],
            Command::NextKey => vec![sc(NONE, Key::ArrowUp)],
            Command::ToggleGrid => vec![sc(NONE, Key::G)],
            Command::ToggleBones => vec![sc(NONE, Key::B)],
            Command::ToggleOnionSkin => vec![sc(NONE, Key::O)],
            Command::SetDeformer(DeformerKind::Rigid) => vec![sc(NONE, Key::Num1)],
            Command::SetDeformer(DeformerKind::LinearBlend) => vec![sc(NONE, Key::Num2)],
            Command::SetDeformer(DeformerKind::BonesBlending) => vec![sc(NONE, Key::Num3)],
            Command::SetDeformer(DeformerKind::DualQuaternion) => vec![sc(NONE, Key::Num4)],
            Command::CameraFront => vec![sc(NONE, Key::F1)],
            Command::CameraSide => vec![sc(NONE, Key::F2)],
            Command::CameraTop => vec![sc(NONE, Key::F3)],
            Command::CameraShoulder => vec![sc(NONE, Key::F4)],
            Command::CameraElbow => vec![sc(NONE, Key::F5)],
            Command::FrameSelection => vec![sc(NONE, Key::F)],
            Command::LookThroughCamera => vec![sc(NONE, Key::Num0)],
            Command::CameraToView => vec![sc(CMD.plus(Modifiers::ALT), Key::Num0)],
            Command::AddCamera => vec![sc(CMD_SHIFT, Key::C)],
            Command::ToggleMarker => vec![sc(NONE, Key::M)],
            Command::BindCameraToMarker => vec![sc(CMD, Key::B)],
            Command::HideSelected => vec![sc(NONE, Key::H)],
            Command::ShowHidden => vec![sc(Modifiers::ALT, Key::H)],
            Command::TogglePreviewRange => vec![sc(CMD.plus(Modifiers::ALT), Key::P)],
            Command::GizmoMove => vec![sc(NONE, Key::W)],
            Command::GizmoTurn => vec![sc(NONE, Key::E)],
            Command::GizmoScale => vec![sc(NONE, Key::S)],
            Command::UndoHistory => vec![sc(CMD.plus(Modifiers::ALT), Key::Z)],
            Command::ReduceKeys => vec![sc(CMD.plus(Modifiers::ALT), Key::K)],
            Command::SmoothKeys => vec![sc(CMD_SHIFT, Key::K)],
            Command::Retarget => vec![sc(CMD.plus(Modifiers::ALT), Key::R)],
            Command::ShowHelp => vec![sc(NONE, Key::F12)],
        }
    }

    /// All shortcuts as text ("Ctrl+P, Space"), as the help window shows them.
    #[must_use]
    pub fn shortcut_text(self, ctx: &egui::Context) -> String {
        self.shortcuts().iter().map(|s| ctx.format_shortcut(s)).collect::<Vec<_>>().join(", ")
    }

    /// Whether the shortcut must not fire while a text field has the keyboard: plain keys and
    /// Shift with a key (a capital letter: Shift+I, Shift+D), and the clipboard and undo keys,
    /// which the text field uses itself.
    #[must_use]
    pub fn yields_to_text_fields(shortcut: &KeyboardShortcut) -> bool {
        let typed = shortcut.modifiers.is_none() || shortcut.modifiers == Modifiers::SHIFT;
        typed || matches!(shortcut.logical_key, Key::C | Key::V | Key::Z | Key::Y)
    }
}

/// What the keyboard asked for in a frame: a command by its shortcut, or copy, cut and paste
/// as the window system delivers them (egui-winit turns Ctrl+C, Ctrl+X and Ctrl+V, and the
/// Copy/Cut/Paste keys, into [`egui::Event::Copy`], [`egui::Event::Cut`] and
/// [`egui::Event::Paste`] with the system clipboard's text, not into key presses).
#[derive(Clone, Debug, PartialEq)]
pub enum Pressed {
    Command(Command),
    Copy,
    Cut,
    Paste(String),
}

/// What the keyboard asked for this frame, one entry per key press and in the order pressed,
/// consuming the key presses of commands. A window that falls behind its input (a slow frame,
/// a held key's repeats) gets several presses in one frame: each is a step (Right pressed three
/// times moves three frames, End then Ctrl+V pastes at the end). While a text field has the
/// keyboard, plain-key shortcuts (R, Space, arrows, 1–4), Shift with a letter (Shift+I,
/// Shift+D), the clipboard and undo keys are left to it, so typing a value or a name does not
/// toggle record mode or IK posing.
#[must_use]
pub fn pressed(ctx: &egui::Context) -> Vec<Pressed> {
    let typing = ctx.text_edit_focused();
    let mut out = Vec::new();
    ctx.input_mut(|input| {
        input.events.retain(|event| {
            let (key, modifiers) = match event {
                egui::Event::Key { key, modifiers, pressed: true, .. } => (*key, *modifiers),
                egui::Event::Copy if !typing => {
                    out.push(Pressed::Copy);
                    return true;
                }
                egui::Event::Cut if !typing => {
                    out.push(Pressed::Cut);
                    return true;
                }
                egui::Event::Paste(text) if !typing => {
                    out.push(Pressed::Paste(text.clone()));
                    return true;
                }
                _ => return true,
            };
            // The first command of `Command::ALL` whose shortcut matches: the more specific
            // shortcuts (Ctrl+Shift+S) come before those they contain (Ctrl+S).
            for command in Command::ALL {
                // Ctrl+C / Ctrl+V arrive as the clipboard events above; their shortcuts are
                // listed for the menus and the help window only.
                if matches!(command, Command::CopyKeys | Command::PasteKeys) {
                    continue;
                }
                let matched = command.shortcuts().iter().any(|shortcut| {
                    !(typing && Command::yields_to_text_fields(shortcut))
                        && shortcut.logical_key == key
                        && modifiers.matches_logically(shortcut.modifiers)
                });
                if matched {
                    out.push(Pressed::Command(command));
                    return false;
                }
            }
            true
        });
    });
    out
}

/// The objects the deformer commands act on: the selected object (`selected`) when it is
/// skinned (has a skeleton), otherwise every skinned object; empty when the scene has none (an
/// MD2 or a static model on its own).
#[must_use]
pub fn deformer_targets(scene: &keyrig_core::Scene, selected: Option<usize>) -> Vec<usize> {
    let objects = &scene.objects;
    let skinned = |o: &usize| objects.get(*o).is_some_and(|object| object.skeleton.is_some());
    match selected.filter(skinned) {
        Some(o) => vec![o],
        None => (0..objects.len()).filter(skinned).collect(),
    }
}

/// The deformer the menu and toolbar show as chosen: the one in effect at this frame (a keyed
/// deformer's value in the evaluated `state`, else the object's setting; as the viewport's
/// overlay names it) of the first of [`deformer_targets`]; `None` without a skinned object.
#[must_use]
pub fn current_deformer(
    scene: &keyrig_core::Scene,
    state: Option<&keyrig_eval::SceneState>,
    selected: Option<usize>,
) -> Option<DeformerKind> {
    let first = *deformer_targets(scene, selected).first()?;
    let set = scene.objects.get(first)?.deformer.kind;
    Some(state.and_then(|s| s.objects.get(first)).map_or(set, |s| s.look.deformer))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashSet;

    #[test]
    fn no_two_commands_share_a_shortcut() {
        let mut seen = HashSet::new();
        for command in Command::ALL {
            for s in &command.shortcuts() {
                let key = (s.modifiers.command, s.modifiers.shift, s.modifiers.alt, s.logical_key);
                assert!(seen.insert(key), "{command:?}");
            }
        }
    }

    /// docs/guide.md lists every command with its shortcuts (PC key names, "Ctrl+P, Space"),
    /// as the help window does.
    #[test]
    fn the_guide_lists_every_shortcut() {
        let guide = include_str!("../../../docs/guide.md");
        for command in Command::ALL {
            let shortcuts: Vec<String> =
                command.shortcuts().iter().map(|s| s.format(&egui::ModifierNames::NAMES, false)).collect();
            let row = format!("| {} | {} |", command.label(), shortcuts.join(", "));
            assert!(guide.contains(&row), "docs/guide.md lacks the row `{row}`");
        }
    }

    /// Typing a capital I or D in a text field types it: Shift+letter shortcuts wait.
    #[test]
    fn shift_letters_yield_to_text_fields() {
        for command in [Command::ToggleIk, Command::DuplicateItem] {
            assert!(command.shortcuts().iter().all(Command::yields_to_text_fields), "{command:?}");
        }
        assert!(!Command::yields_to_text_fields(&sc(CMD_SHIFT, Key::S)), "Save as works while typing");
    }

    /// Key presses and clipboard events that reach one frame together (a window behind its
    /// input) are each an entry, in the order they came; other events stay for the rest of
    /// the UI, and so do the clipboard events (a text field may want them).
    #[test]
    fn presses_in_one_frame_are_each_an_entry_in_order() {
        let ctx = egui::Context::default();
        let key = |key: Key, pressed: bool| egui::Event::Key {
            key,
            physical_key: None,
            pressed,
            repeat: false,
            modifiers: Modifiers::NONE,
        };
        let mut events = Vec::new();
        for k in [Key::ArrowRight, Key::ArrowRight, Key::R] {
            events.push(key(k, true));
            events.push(key(k, false));
        }
        events.push(egui::Event::Copy);
        events.push(key(Key::End, true));
        events.push(egui::Event::Paste("text".into()));
        events.push(egui::Event::Cut);
        events.push(egui::Event::Text("x".into()));
        let input = egui::RawInput { events, ..Default::default() };
        let mut got = Vec::new();
        let mut left = 0;
        let _ = ctx.run_ui(input, |ui| {
            got = pressed(ui.ctx());
            left = ui.input(|i| i.events.len());
        });
        assert_eq!(
            got,
            [
                Pressed::Command(Command::NextFrame),
                Pressed::Command(Command::NextFrame),
                Pressed::Command(Command::ToggleRecord),
                Pressed::Copy,
                Pressed::Command(Command::LastFrame),
                Pressed::Paste("text".into()),
                Pressed::Cut,
            ]
        );
        assert_eq!(left, 7, "the three releases, the clipboard events and the text stay");
    }

    #[test]
    fn every_command_has_label_tooltip_and_shortcut() {
        for command in Command::ALL {
            assert!(!command.label().is_empty());
            assert!(!command.tooltip().is_empty());
            assert!(!command.shortcuts().is_empty(), "{command:?}");
        }
    }
}

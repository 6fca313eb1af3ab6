//! The one way the editor changes: panels, menus, dialogs and shortcuts push [`Action`]s into
//! the frame's [`Actions`] queue while they are laid out, reading the document, the session and
//! the evaluated scene from a read-only [`crate::context::FrameCtx`]. At the end of the frame
//! [`crate::app::EditorApp::apply_actions`] applies them in the order they were pushed, each
//! once, through one function — as rerun's viewer runs its queue of system commands. Every
//! panel of the next frame draws from the state after them.
//!
//! Undo steps are what they always were: an [`Edit`] is one [`crate::document::Document::edit`]
//! (one undo step) or part of one [`crate::document::Document::edit_continuous`] group (one step
//! per drag, closed when the pointer is released).

use std::collections::{BTreeSet, HashMap};
use std::path::PathBuf;

use glam::Quat;
use keyrig_core::Camera;
use keyrig_edit::SceneEdit;

use crate::commands::Command;
use crate::files::{BackgroundImport, DialogPurpose};
use crate::session::{KeyRef, Selected};
use crate::view::RenderStyle;
use keyrig_edit::channels::{ChannelId, ChannelValue, Turn};

/// What to do once unsaved changes have been dealt with.
#[derive(Clone, Debug, PartialEq)]
pub enum PendingAction {
    New,
    Open(Option<PathBuf>),
    Quit,
}

/// The answer to the unsaved-changes dialog.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unsaved {
    Save,
    Discard,
    Cancel,
}

/// One change the editor applies at the end of the frame.
pub enum Action {
    /// A user command (menus, toolbar, shortcuts, context menus).
    Command(Command),
    /// The clipboard events: Ctrl+C, Ctrl+X, and Ctrl+V with the system clipboard's text.
    Copy,
    Cut,
    Paste(String),
    /// A change of the document.
    Edit(Edit),
    /// Ends the open continuous edit: a typed value is its own undo step, and a released pointer
    /// ends a drag's step.
    CloseGroup,
    /// A change of the session (selection, clock, IK posing).
    Session(SessionChange),
    /// A change of the view (camera, viewport options, onion skin, help window).
    View(ViewChange),
    /// Goes back (undo) or forward (redo) to the state after this many undo steps (a click in
    /// the undo history).
    UndoTo(usize),
    /// A status-bar message, or an error.
    Info(String),
    Error(String),
    /// Renames an object, joint or light (the outliner's name field).
    Rename {
        item: Selected,
        name: String,
    },
    /// Adds, applies, renames or deletes a pose of the pose library (inspector).
    PoseLibrary(PoseLibraryAction),
    /// Keys the solved rotations of an IK constraint's chain at every frame (inspector).
    BakeIk {
        object: usize,
        constraint: usize,
    },
    /// Switches a child-of constraint's parent to `target` at the current frame, without a
    /// jump (inspector; `keyrig_eval::switch_parent`).
    SwitchParent {
        object: usize,
        constraint: usize,
        target: keyrig_core::AimTarget,
    },
    /// Adds an IK constraint on the IK-posing chain that ends at `joint` (inspector).
    KeepIk {
        object: usize,
        joint: usize,
    },
    /// Frames objects once their deformed bounds are known (after an import or opening a model).
    FrameObjects(Vec<usize>),
    /// Asks before losing unsaved changes ([`crate::app::EditorApp::request`]).
    Request(PendingAction),
    /// The unsaved-changes dialog's answer.
    ResolveUnsaved(Unsaved),
    /// The recovery offer: recover the autosaved scene (true) or discard it.
    Recover(bool),
    /// A file picked in the file dialog.
    FilePicked(DialogPurpose, PathBuf),
    /// Opens the file dialog for the reference image (View ▸ Reference image).
    ChooseReferenceImage,
    /// Sets the import scale from what the user typed or chose (File ▸ Import scale); a bad
    /// number is refused with a message.
    ImportScale(String),
    /// A file dropped on the window.
    Dropped(PathBuf),
    /// A model import that finished on its thread.
    ImportFinished(BackgroundImport),
    /// Starts rendering the scene as the Render animation dialog says.
    StartRender {
        blast: crate::playblast::Playblast,
        through: Option<crate::view::LookThrough>,
    },
    /// Stops the running render (its movie is not written).
    CancelRender,
    /// Adds an empty, a primitive, a light or a camera where the view looks (the Add menu).
    Add(keyrig_edit::scene_add::AddKind),
}

/// A change of the document: one undo step, or one step per gesture.
pub enum Edit {
    /// A pose change made with a gizmo or the inspector: a key in record mode, else a pose
    /// override of an animated channel or the value of a static one
    /// ([`crate::app::EditorApp::apply_pose`]); `group` merges a drag into one undo step.
    Pose { id: ChannelId, value: ChannelValue, group: String },
    /// Sets the keys of translation channel `id` to `keys` (time, value) and its static value to
    /// `rest` (what it plays muted): a copy placed by
    /// Shift+D's grab moves with its whole motion ([`crate::app::EditorApp::apply_place_keys`]);
    /// `group` merges the grab into one undo step.
    PlaceKeys { id: ChannelId, keys: Vec<(f64, glam::Vec3)>, rest: glam::Vec3, group: String },
    /// A rotation turned with a gizmo ring or the twist field, with the spin of its key in
    /// record mode ([`crate::app::EditorApp::apply_turn`]).
    Turn { id: ChannelId, turn: Turn, group: String },
    /// The rotations one frame of an IK drag solved ([`crate::app::EditorApp::apply_ik_pose`]).
    IkPose { rotations: Vec<(ChannelId, Quat)>, label: String },
    /// Moves every selected key by `seconds` (one continuous edit, refused when a key would
    /// land on another); whether it moved is reported under `ticket` ([`EditResults`]).
    MoveSelectedKeys { seconds: f64, ticket: Ticket },
    /// Adds `delta` to component `component` of every selected key's value (an Euler angle in
    /// degrees for rotations, or with `twist` the twist about the bone axis).
    ShiftSelectedValues { component: usize, delta: f32, twist: bool },
    /// Any other change of the scene, as data ([`SceneEdit`], named by its own undo label): one
    /// undo step, or with `group` part of the continuous edit of that name.
    Scene { edit: SceneEdit, group: Option<String> },
}

impl Edit {
    /// A change of the scene that is one undo step.
    #[must_use]
    pub fn scene(edit: SceneEdit) -> Self {
        Edit::Scene { edit, group: None }
    }

    /// A change of the scene that joins the continuous edit `group` (one drag).
    #[must_use]
    pub fn continuous(group: impl Into<String>, edit: SceneEdit) -> Self {
        Edit::Scene { edit, group: Some(group.into()) }
    }
}

/// What the Pose library section asks for.
#[derive(Clone, Debug, PartialEq)]
pub enum PoseLibraryAction {
    /// Saves the selection's pose at the current frame under this name ("Pose" when empty).
    Add(String),
    /// Applies pose `index` to the selection, mirrored or not.
    Apply {
        index: usize,
        mirrored: bool,
    },
    Rename {
        index: usize,
        name: String,
    },
    Delete(usize),
}

/// A change of the session.
#[derive(Clone, Debug)]
pub enum SessionChange {
    /// Selects `item` alone (`None`: no item), as a plain click.
    SelectOnly(Option<Selected>),
    /// Shift/Ctrl-click: adds `item` as the active item, or removes it when it was selected.
    Toggle(Selected),
    /// Adds `item` unless it is selected already.
    Add(Selected),
    /// Replaces the selected keys.
    SetKeys(BTreeSet<KeyRef>),
    /// Adds keys to the selection.
    AddKeys(Vec<KeyRef>),
    /// Takes keys out of the selection.
    RemoveKeys(Vec<KeyRef>),
    /// Moves the clock to a whole frame (inside the range); pose overrides are dropped.
    SetFrame(i32),
    /// Every-frame playback on or off.
    EveryFrame(bool),
    /// The active keying set: what `I` keys ([`crate::keying_sets`]).
    KeyingSet(crate::keying_sets::KeyingSet),
    /// The length of the IK chain that ends at a joint.
    ChainBones { object: usize, joint: usize, bones: usize },
    /// The pole an IK drag ended with, kept for the chain's next drag.
    RememberPole { chain: Box<crate::ik_posing::PosedChain>, pole: glam::Vec3 },
}

/// A change of the view.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewChange {
    Camera(Camera),
    Style(RenderStyle),
    Textures(bool),
    ResolutionScale(f32),
    Antialiasing(bool),
    Onion(crate::onion::OnionSkin),
    ShowHelp(bool),
    ShowUndoHistory(bool),
    /// Look through a scene camera, or (None) through the orbit camera again.
    LookThrough(Option<crate::view::LookThrough>),
    ShowRender(bool),
}

/// Names one pushed edit whose outcome the panel that pushed it reads in the next frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Ticket(u64);

/// Outcomes of the last frame's edits that report one (a key move is refused when a key would
/// land on another: the gesture then keeps what it had applied).
#[derive(Clone, Debug, Default)]
pub struct EditResults {
    moved: HashMap<Ticket, bool>,
}

impl EditResults {
    /// Whether the edit under `ticket` changed the document (false when refused or unknown).
    #[must_use]
    pub fn moved(&self, ticket: Ticket) -> bool {
        self.moved.get(&ticket).copied().unwrap_or(false)
    }

    /// Records the outcome of the edit under `ticket`.
    pub fn record(&mut self, ticket: Ticket, moved: bool) {
        self.moved.insert(ticket, moved);
    }

    /// Forgets the outcomes of an older frame.
    pub fn clear(&mut self) {
        self.moved.clear();
    }
}

/// The frame's queue of actions, in the order they were pushed.
#[derive(Default)]
pub struct Actions {
    queue: std::collections::VecDeque<Action>,
    next_ticket: u64,
}

impl Actions {
    /// Queues an action.
    pub fn push(&mut self, action: Action) {
        self.queue.push_back(action);
    }

    /// Queues a document edit.
    pub fn edit(&mut self, edit: Edit) {
        self.push(Action::Edit(edit));
    }

    /// Queues a session change.
    pub fn session(&mut self, change: SessionChange) {
        self.push(Action::Session(change));
    }

    /// Queues a view change.
    pub fn view(&mut self, change: ViewChange) {
        self.push(Action::View(change));
    }

    /// Queues a command.
    pub fn command(&mut self, command: Command) {
        self.push(Action::Command(command));
    }

    /// A new ticket for an edit whose outcome the pusher wants to read.
    pub fn ticket(&mut self) -> Ticket {
        self.next_ticket += 1;
        Ticket(self.next_ticket)
    }

    /// The first action still queued, taking it.
    pub fn pop(&mut self) -> Option<Action> {
        self.queue.pop_front()
    }

    /// Whether nothing is queued.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }
}

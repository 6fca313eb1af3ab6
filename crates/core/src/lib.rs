//! keyrig-core: keys, tracks, Kochanek–Bartels (TCB) and Squad interpolation, and the scene
//! document. Pure: no file I/O, no GPU, no UI.

pub mod action;
pub mod action_keys;
pub mod attributes;
pub mod camera_object;
pub mod channel;
pub mod channel_id;
pub mod channel_value;
pub mod clip;
pub mod ik;
pub mod ik_constraint;
pub mod key;
pub mod material;
pub mod object_constraint;
pub mod pose_library;
pub mod quat;
pub mod rotation_mode;
pub mod scene;
pub mod sound;
pub mod track;
pub mod validate;

pub use action::{Action, ActionChannel, ActionError, ActionKeys, ActionSummary, DEFAULT_ACTION};
pub use attributes::{LightAttributes, ObjectAttributes};
pub use camera_object::{Aim, AimTarget, Lens, Marker, Projection, RenderSize, SceneCamera};
pub use channel_id::attribute_id;
pub use channel_id::attribute_id::{AttributeId, AttributeProperty};
pub use clip::{ClipTrack, Extrapolation, Layer, LayerMode, Strip, StripAt, StripBlend};
pub use key::{
    Animated, Cycle, Cycles, Interpolation, Key, KeyType, Keys, RawTrack, Spin, Tcb, MAX_SPIN_TURNS,
};
pub use material::{FilterMode, Material, Sampler, TextureError, TextureImage, WrapMode};
pub use object_constraint::{AimAxis, ChildOfParent, ConstraintKind, ObjectConstraint};
pub use pose_library::{NamedPose, PoseValue, ReferenceImage};
pub use rotation_mode::{EulerOrder, RotationMode};
pub use scene::{
    Camera, DeformerKind, DeformerSettings, FrameRange, IkConstraint, Joint, Light, LightKind, MeshSource,
    Object, Problem, ProceduralMesh, Scene, Skeleton, MD2_DEFAULT_FPS,
};
pub use sound::{SoundClip, SummaryBuilder, WaveformSummary};
pub use track::{
    check_cycles, AnimatedTrack, SpinProblem, TangentSide, Track, TrackEnd, TrackError, TrackValue,
};

//! keyrig-io: everything that touches a file. RON scene files (versioned, checked, saved
//! atomically), the built-in demo scene, glTF import/export, MD2 import, and VRML97 / X3D /
//! Open Inventor import ([`vrml`]), BVH motion capture import and export ([`bvh`]), and sound clips' files decoded into waveform summaries
//! ([`sound`]).

pub mod bvh;
pub mod demo;
pub mod fbx;
pub mod file_io;
pub mod gltf_camera;
pub mod gltf_export;
pub mod gltf_import;
pub mod gltf_pointer;
pub mod md2;
pub mod message;
pub mod model;
pub mod project;
pub mod reference_image;
pub mod scene_file;
mod scene_locate;
mod scene_text;
mod scene_v1;
pub mod sound;
pub mod vrml;

pub use scene_file::{load, save, LocatedProblem, SceneFileError};

//! keyrig-tests: cross-crate end-to-end tests (see `tests/`); the library itself is empty.
//!
//! Its doctests are the Rust examples of the documentation: every ```` ```rust ```` block of
//! the files below is compiled and run by `cargo test -p keyrig-tests --doc`
//! (`crates/editor/tests/docs_run.rs` checks that each Markdown file with Rust blocks is listed
//! here).

/// The Markdown files whose Rust blocks are doctests.
#[cfg(doctest)]
pub mod docs {
    #[doc = include_str!("../docs/channels.md")]
    pub struct Channels;
    #[doc = include_str!("../docs/interpolation.md")]
    pub struct Interpolation;
    #[doc = include_str!("../docs/skinning.md")]
    pub struct Skinning;
    #[doc = include_str!("../docs/binding.md")]
    pub struct Binding;
    #[doc = include_str!("../docs/rendering.md")]
    pub struct Rendering;
}

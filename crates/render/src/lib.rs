//! keyrig render

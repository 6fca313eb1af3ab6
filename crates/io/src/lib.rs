//! keyrig io

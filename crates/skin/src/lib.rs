//! keyrig skin

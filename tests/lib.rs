//! Shared helpers for keyrig end-to-end tests.

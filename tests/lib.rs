//! keyrig-tests: cross-crate end-to-end tests (see `tests/`); the library itself is empty.

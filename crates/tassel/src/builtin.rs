//! Builtin character.

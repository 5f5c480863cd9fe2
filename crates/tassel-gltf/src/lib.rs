//! glTF 2.0 import and export for Tassel.

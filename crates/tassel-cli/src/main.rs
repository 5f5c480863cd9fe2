//! The `tassel` command.
fn main() {}

//! The `lumiview` command-line tool.
fn main() {}

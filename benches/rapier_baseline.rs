//! Placeholder; replaced by the real rapier baseline bench.
fn main() {}

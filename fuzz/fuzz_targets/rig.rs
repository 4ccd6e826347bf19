//! rig.toml with the shipped recordings beside it: loaded or refused, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../entries.rs"]
mod entries;

fuzz_target!(|data: &[u8]| {
    entries::rig(data);
});

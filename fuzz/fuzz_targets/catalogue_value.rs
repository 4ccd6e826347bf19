//! Catalogue values ("6.3 bar", "1,450 rpm", …): read or refused, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../entries.rs"]
mod entries;

fuzz_target!(|data: &[u8]| {
    entries::catalogue_value(data);
});

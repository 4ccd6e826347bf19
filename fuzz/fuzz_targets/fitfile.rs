//! Fit files (vanefit.fit/1): read or refused, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../entries.rs"]
mod entries;

fuzz_target!(|data: &[u8]| {
    entries::fit_file(data);
});

//! The files `merge` reads back from a batch folder (batch.json, status.json, fit.json,
//! diagnosis.json): summarised or refused, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;

#[path = "../entries.rs"]
mod entries;

fuzz_target!(|data: &[u8]| {
    entries::batch_files(data);
});

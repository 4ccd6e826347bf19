//! Hardening: closed stdout, locks, exit codes and numerical faults ([`hardening`]), full,
//! read-only and missing output folders ([`disk_faults`]), runs killed at any moment
//! ([`kill_anywhere`]) and the fuzz corpus replayed ([`fuzz_corpus`]).

#[path = "../common/mod.rs"]
mod common;
mod disk_faults;
mod fuzz_corpus;
mod hardening;
mod kill_anywhere;

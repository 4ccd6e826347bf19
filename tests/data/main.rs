//! Data in: catalogue pages ([`catalogue_input`]), the import of recordings and rig files
//! ([`import_hardening`]) and the one gate every command applies to values ([`one_gate`]).

mod catalogue_input;
#[path = "../common/mod.rs"]
mod common;
mod import_hardening;
mod one_gate;

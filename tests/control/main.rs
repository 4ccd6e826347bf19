//! `vanefit control`: the speed-control studies of paper §5 against the independent twin
//! ([`twin_studies`]): throttling at either port, the frequency response, the PI design's
//! margins, the step and load-disturbance responses of the loop, and the start-up on a
//! pressure ramp.

extern crate twin;
mod twin_studies;

//! The FMI 2.0 C interface of vanefit's motor (model exchange and co-simulation): the
//! shared library that `vanefit export-fmu` packs into an FMU as
//! `binaries/linux64/vanefit_fmu.so` (docs/fmu.md).
//!
//! Only the C calling convention lives here: every call finds its instance, converts the C
//! arguments and calls `vanefit::export::fmu::MotorFmu`, which holds the model (the
//! same code as `vanefit simulate`). The fit comes from the FMU's `resources/fit.json`,
//! checked against the GUID of `modelDescription.xml`. No call unwinds into C: a panic
//! becomes `fmi2Fatal`.

#![allow(non_snake_case, clippy::missing_safety_doc)]

use std::ffi::{c_char, c_int, c_uint, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use vanefit::data::FitFile;
use vanefit::export::fmu::vr;
use vanefit::export::fmu::MotorFmu;
use vanefit::export::fmu::{guid, RESOURCE_FIT};
use vanefit::model::N_STATES;

/// fmi2Status.
pub type Status = c_int;
/// fmi2OK.
pub const OK: Status = 0;
/// fmi2Warning.
pub const WARNING: Status = 1;
/// fmi2Discard.
pub const DISCARD: Status = 2;
/// fmi2Error.
pub const ERROR: Status = 3;
/// fmi2Fatal.
pub const FATAL: Status = 4;

/// fmi2CallbackLogger: (componentEnvironment, instanceName, status, category, message, ...).
pub type Logger =
    unsafe extern "C" fn(*mut c_void, *const c_char, Status, *const c_char, *const c_char, ...);

/// fmi2CallbackFunctions.
#[repr(C)]
pub struct CallbackFunctions {
    /// The logger.
    pub logger: Option<Logger>,
    /// allocateMemory (unused: Rust allocates).
    pub allocate_memory: *const c_void,
    /// freeMemory (unused).
    pub free_memory: *const c_void,
    /// stepFinished (unused: steps are synchronous).
    pub step_finished: *const c_void,
    /// componentEnvironment, passed back to the logger.
    pub component_environment: *mut c_void,
}

/// fmi2EventInfo.
#[repr(C)]
pub struct EventInfo {
    /// newDiscreteStatesNeeded.
    pub new_discrete_states_needed: c_int,
    /// terminateSimulation.
    pub terminate_simulation: c_int,
    /// nominalsOfContinuousStatesChanged.
    pub nominals_changed: c_int,
    /// valuesOfContinuousStatesChanged.
    pub values_changed: c_int,
    /// nextEventTimeDefined.
    pub next_event_time_defined: c_int,
    /// nextEventTime.
    pub next_event_time: f64,
}

/// One instance of the FMU.
struct Instance {
    name: CString,
    env: *mut c_void,
    logger: Option<Logger>,
    logging_on: bool,
    model: MotorFmu,
}

impl Instance {
    fn log(&self, status: Status, message: &str) {
        if status != OK || self.logging_on {
            emit(self.logger, self.env, &self.name, status, message);
        }
    }
}

/// Sends a message to the importer's logger, if it gave one.
fn emit(logger: Option<Logger>, env: *mut c_void, name: &CStr, status: Status, message: &str) {
    if let Some(logger) = logger {
        let msg = CString::new(message.replace('\0', " ")).unwrap_or_default();
        let category = if status >= ERROR {
            c"logStatusError"
        } else {
            c"logAll"
        };
        // SAFETY: the importer's logger with its own environment; "%s" keeps the message
        // from being read as a format.
        unsafe {
            logger(
                env,
                name.as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                msg.as_ptr(),
            )
        };
    }
}

/// Runs `f` on the instance behind `c`, logging an error as `fmi2Error` and a panic as
/// `fmi2Fatal`.
fn with(c: *mut c_void, f: impl FnOnce(&mut Instance) -> Result<(), String>) -> Status {
    if c.is_null() {
        return ERROR;
    }
    // SAFETY: `c` is a pointer fmi2Instantiate returned and fmi2FreeInstance has not freed.
    let inst = unsafe { &mut *(c as *mut Instance) };
    match catch_unwind(AssertUnwindSafe(|| f(inst))) {
        Ok(Ok(())) => OK,
        Ok(Err(msg)) => {
            inst.log(ERROR, &msg);
            ERROR
        }
        Err(_) => {
            inst.log(FATAL, "internal error (panic) in the FMU");
            FATAL
        }
    }
}

/// A slice from a C pointer and length (empty for a null pointer or zero length).
unsafe fn slice<'a, T>(p: *const T, n: usize) -> &'a [T] {
    if p.is_null() || n == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(p, n)
    }
}

/// A mutable slice from a C pointer and length.
unsafe fn slice_mut<'a, T>(p: *mut T, n: usize) -> &'a mut [T] {
    if p.is_null() || n == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(p, n)
    }
}

unsafe fn string(p: *const c_char) -> String {
    if p.is_null() {
        String::new()
    } else {
        CStr::from_ptr(p).to_string_lossy().into_owned()
    }
}

/// The folder a `file:` URI names (`file:///a/b`, `file:/a/b`, `file://localhost/a/b`),
/// percent-escapes decoded; a plain path is taken as it is.
pub fn resource_dir(uri: &str) -> PathBuf {
    let rest = uri
        .strip_prefix("file://localhost")
        .or_else(|| uri.strip_prefix("file://"))
        .or_else(|| uri.strip_prefix("file:"))
        .unwrap_or(uri);
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    PathBuf::from(String::from_utf8_lossy(&out).into_owned())
}

/// Reads the fit in the resources and checks it against the GUID.
fn load_model(resources: &str, expected_guid: &str) -> Result<MotorFmu, String> {
    let path = resource_dir(resources).join(RESOURCE_FIT);
    let text = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let id = guid(&text);
    if id != expected_guid {
        return Err(format!(
            "{} has GUID {id}, the model description {expected_guid}: the FMU was altered",
            path.display()
        ));
    }
    let fit = FitFile::parse(&path, &String::from_utf8_lossy(&text)).map_err(|e| e.to_string())?;
    MotorFmu::new(fit).map_err(|e| e.to_string())
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: *const c_char,
    _fmu_type: c_int,
    fmu_guid: *const c_char,
    resource_location: *const c_char,
    functions: *const CallbackFunctions,
    _visible: c_int,
    logging_on: c_int,
) -> *mut c_void {
    let (logger, env) = match functions.as_ref() {
        Some(f) => (f.logger, f.component_environment),
        None => (None, std::ptr::null_mut()),
    };
    let name = CString::new(string(instance_name)).unwrap_or_default();
    let made = catch_unwind(|| load_model(&string(resource_location), &string(fmu_guid)));
    let model = match made {
        Ok(Ok(m)) => m,
        Ok(Err(msg)) => return fail_instantiate(logger, env, &name, &msg),
        Err(_) => return fail_instantiate(logger, env, &name, "internal error (panic)"),
    };
    let inst = Box::new(Instance {
        name,
        env,
        logger,
        logging_on: logging_on != 0,
        model,
    });
    Box::into_raw(inst) as *mut c_void
}

fn fail_instantiate(
    logger: Option<Logger>,
    env: *mut c_void,
    name: &CStr,
    msg: &str,
) -> *mut c_void {
    emit(logger, env, name, ERROR, &format!("fmi2Instantiate: {msg}"));
    std::ptr::null_mut()
}

#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: *mut c_void) {
    if !c.is_null() {
        drop(Box::from_raw(c as *mut Instance));
    }
}

#[no_mangle]
pub extern "C" fn fmi2SetDebugLogging(
    c: *mut c_void,
    logging_on: c_int,
    _n: usize,
    _categories: *const *const c_char,
) -> Status {
    with(c, |i| {
        i.logging_on = logging_on != 0;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetupExperiment(
    c: *mut c_void,
    _tolerance_defined: c_int,
    _tolerance: f64,
    start_time: f64,
    _stop_time_defined: c_int,
    _stop_time: f64,
) -> Status {
    with(c, |i| {
        i.model.time_s = start_time;
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterInitializationMode(c: *mut c_void) -> Status {
    with(c, |_| Ok(()))
}

#[no_mangle]
pub extern "C" fn fmi2ExitInitializationMode(c: *mut c_void) -> Status {
    with(c, |i| i.model.initialize().map_err(|e| e.to_string()))
}

#[no_mangle]
pub extern "C" fn fmi2Terminate(c: *mut c_void) -> Status {
    with(c, |_| Ok(()))
}

#[no_mangle]
pub extern "C" fn fmi2Reset(c: *mut c_void) -> Status {
    with(c, |i| {
        let fresh = MotorFmu::new(i.model.fit().clone()).map_err(|e| e.to_string())?;
        i.model = fresh;
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: *mut c_void,
    refs: *const c_uint,
    n: usize,
    values: *mut f64,
) -> Status {
    let (refs, values) = (slice(refs, n), slice_mut(values, n));
    with(c, |i| {
        for (r, v) in refs.iter().zip(values.iter_mut()) {
            *v = i.model.get_real(*r).map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: *mut c_void,
    refs: *const c_uint,
    n: usize,
    values: *const f64,
) -> Status {
    let (refs, values) = (slice(refs, n), slice(values, n));
    with(c, |i| {
        for (r, v) in refs.iter().zip(values) {
            i.model.set_real(*r, *v).map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: *mut c_void,
    refs: *const c_uint,
    n: usize,
    values: *mut c_int,
) -> Status {
    let (refs, values) = (slice(refs, n), slice_mut(values, n));
    with(c, |i| {
        for (r, v) in refs.iter().zip(values.iter_mut()) {
            if *r != vr::START_STEADY {
                return Err(format!("no Boolean variable with value reference {r}"));
            }
            *v = c_int::from(i.model.start_steady);
        }
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: *mut c_void,
    refs: *const c_uint,
    n: usize,
    values: *const c_int,
) -> Status {
    let (refs, values) = (slice(refs, n), slice(values, n));
    with(c, |i| {
        for (r, v) in refs.iter().zip(values) {
            if *r != vr::START_STEADY {
                return Err(format!("no Boolean variable with value reference {r}"));
            }
            i.model.start_steady = *v != 0;
        }
        Ok(())
    })
}

/// Integer and String variables: the FMU has none; asking for zero of them is fine.
fn none_of_type(c: *mut c_void, n: usize, kind: &str) -> Status {
    with(c, |_| {
        if n == 0 {
            Ok(())
        } else {
            Err(format!("the FMU has no {kind} variables"))
        }
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetInteger(
    c: *mut c_void,
    _r: *const c_uint,
    n: usize,
    _v: *mut c_int,
) -> Status {
    none_of_type(c, n, "Integer")
}

#[no_mangle]
pub extern "C" fn fmi2SetInteger(
    c: *mut c_void,
    _r: *const c_uint,
    n: usize,
    _v: *const c_int,
) -> Status {
    none_of_type(c, n, "Integer")
}

#[no_mangle]
pub extern "C" fn fmi2GetString(
    c: *mut c_void,
    _r: *const c_uint,
    n: usize,
    _v: *mut *const c_char,
) -> Status {
    none_of_type(c, n, "String")
}

#[no_mangle]
pub extern "C" fn fmi2SetString(
    c: *mut c_void,
    _r: *const c_uint,
    n: usize,
    _v: *const *const c_char,
) -> Status {
    none_of_type(c, n, "String")
}

/// What the FMU does not offer (its capability flags say so): an error to the caller.
fn unsupported(c: *mut c_void, what: &str) -> Status {
    with(c, |_| Err(format!("{what} is not supported by this FMU")))
}

#[no_mangle]
pub extern "C" fn fmi2GetFMUstate(c: *mut c_void, _s: *mut *mut c_void) -> Status {
    unsupported(c, "fmi2GetFMUstate")
}

#[no_mangle]
pub extern "C" fn fmi2SetFMUstate(c: *mut c_void, _s: *mut c_void) -> Status {
    unsupported(c, "fmi2SetFMUstate")
}

#[no_mangle]
pub extern "C" fn fmi2FreeFMUstate(c: *mut c_void, _s: *mut *mut c_void) -> Status {
    unsupported(c, "fmi2FreeFMUstate")
}

#[no_mangle]
pub extern "C" fn fmi2SerializedFMUstateSize(
    c: *mut c_void,
    _s: *mut c_void,
    _n: *mut usize,
) -> Status {
    unsupported(c, "fmi2SerializedFMUstateSize")
}

#[no_mangle]
pub extern "C" fn fmi2SerializeFMUstate(
    c: *mut c_void,
    _s: *mut c_void,
    _b: *mut c_char,
    _n: usize,
) -> Status {
    unsupported(c, "fmi2SerializeFMUstate")
}

#[no_mangle]
pub extern "C" fn fmi2DeSerializeFMUstate(
    c: *mut c_void,
    _b: *const c_char,
    _n: usize,
    _s: *mut *mut c_void,
) -> Status {
    unsupported(c, "fmi2DeSerializeFMUstate")
}

#[no_mangle]
pub extern "C" fn fmi2GetDirectionalDerivative(
    c: *mut c_void,
    _u: *const c_uint,
    _nu: usize,
    _z: *const c_uint,
    _nz: usize,
    _dv: *const f64,
    _dz: *mut f64,
) -> Status {
    unsupported(c, "fmi2GetDirectionalDerivative")
}

// --- Model exchange ---------------------------------------------------------------------

#[no_mangle]
pub extern "C" fn fmi2EnterEventMode(c: *mut c_void) -> Status {
    with(c, |_| Ok(()))
}

/// No discrete states and no time events: the event iteration ends at once.
#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(c: *mut c_void, info: *mut EventInfo) -> Status {
    with(c, |_| {
        if let Some(info) = info.as_mut() {
            *info = EventInfo {
                new_discrete_states_needed: 0,
                terminate_simulation: 0,
                nominals_changed: 0,
                values_changed: 0,
                next_event_time_defined: 0,
                next_event_time: 0.0,
            };
        }
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2EnterContinuousTimeMode(c: *mut c_void) -> Status {
    with(c, |_| Ok(()))
}

#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: *mut c_void,
    _no_set_prior: c_int,
    enter_event_mode: *mut c_int,
    terminate: *mut c_int,
) -> Status {
    with(c, |_| {
        if let Some(e) = enter_event_mode.as_mut() {
            *e = 0;
        }
        if let Some(t) = terminate.as_mut() {
            *t = 0;
        }
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2SetTime(c: *mut c_void, time: f64) -> Status {
    with(c, |i| {
        i.model.time_s = time;
        Ok(())
    })
}

fn check_states(n: usize) -> Result<(), String> {
    if n == N_STATES {
        Ok(())
    } else {
        Err(format!("the FMU has {N_STATES} continuous states, not {n}"))
    }
}

#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: *mut c_void,
    x: *const f64,
    n: usize,
) -> Status {
    let x = slice(x, n);
    with(c, |i| {
        check_states(n)?;
        i.model.set_states(x);
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(c: *mut c_void, x: *mut f64, n: usize) -> Status {
    let x = slice_mut(x, n);
    with(c, |i| {
        check_states(n)?;
        x.copy_from_slice(&i.model.x);
        Ok(())
    })
}

#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(c: *mut c_void, dx: *mut f64, n: usize) -> Status {
    let dx = slice_mut(dx, n);
    with(c, |i| {
        check_states(n)?;
        dx.copy_from_slice(&i.model.derivatives());
        Ok(())
    })
}

/// Typical magnitudes: 1 bar on pressures, 1000 rad/s on speed (absolute tolerances of an
/// importer's integrator scale with them).
#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: *mut c_void,
    x: *mut f64,
    n: usize,
) -> Status {
    let x = slice_mut(x, n);
    with(c, |_| {
        check_states(n)?;
        x.copy_from_slice(&[1e5, 1e5, 1e5, 1e3]);
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetEventIndicators(c: *mut c_void, _g: *mut f64, n: usize) -> Status {
    with(c, |_| {
        if n == 0 {
            Ok(())
        } else {
            Err(format!("the FMU has no event indicators, not {n}"))
        }
    })
}

// --- Co-simulation ----------------------------------------------------------------------

/// First derivatives of inputs for the next step (`canInterpolateInputs`): the step then
/// moves the inputs along them. Higher orders are refused.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: *mut c_void,
    refs: *const c_uint,
    n: usize,
    order: *const c_int,
    values: *const f64,
) -> Status {
    let (refs, order, values) = (slice(refs, n), slice(order, n), slice(values, n));
    with(c, |i| {
        for ((r, k), v) in refs.iter().zip(order).zip(values) {
            if *k != 1 {
                return Err(format!(
                    "input derivatives of order {k}: only order 1 is supported"
                ));
            }
            i.model.set_input_slope(*r, *v).map_err(|e| e.to_string())?;
        }
        Ok(())
    })
}

#[no_mangle]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: *mut c_void,
    _r: *const c_uint,
    _n: usize,
    _order: *const c_int,
    _v: *mut f64,
) -> Status {
    unsupported(c, "fmi2GetRealOutputDerivatives")
}

/// One communication step: Rodas4 from the current communication point over `h` with the
/// inputs held.
#[no_mangle]
pub extern "C" fn fmi2DoStep(c: *mut c_void, t: f64, h: f64, _no_set_prior: c_int) -> Status {
    with(c, |i| {
        i.model.time_s = t;
        i.model.do_step(h).map_err(|e| e.to_string())
    })
}

#[no_mangle]
pub extern "C" fn fmi2CancelStep(c: *mut c_void) -> Status {
    unsupported(c, "fmi2CancelStep")
}

/// Steps are synchronous: there is never a pending status to ask about.
fn no_status(c: *mut c_void) -> Status {
    let s = with(c, |_| {
        Err("the FMU's steps are synchronous: no status to ask".into())
    });
    if s == ERROR {
        DISCARD
    } else {
        s
    }
}

#[no_mangle]
pub extern "C" fn fmi2GetStatus(c: *mut c_void, _k: c_int, _v: *mut c_int) -> Status {
    no_status(c)
}

#[no_mangle]
pub extern "C" fn fmi2GetRealStatus(c: *mut c_void, _k: c_int, _v: *mut f64) -> Status {
    no_status(c)
}

#[no_mangle]
pub extern "C" fn fmi2GetIntegerStatus(c: *mut c_void, _k: c_int, _v: *mut c_int) -> Status {
    no_status(c)
}

#[no_mangle]
pub extern "C" fn fmi2GetBooleanStatus(c: *mut c_void, _k: c_int, _v: *mut c_int) -> Status {
    no_status(c)
}

#[no_mangle]
pub extern "C" fn fmi2GetStringStatus(c: *mut c_void, _k: c_int, _v: *mut *const c_char) -> Status {
    no_status(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resource_uris_become_folders() {
        assert_eq!(
            resource_dir("file:///tmp/a%20b/resources"),
            PathBuf::from("/tmp/a b/resources")
        );
        assert_eq!(resource_dir("file:/tmp/x"), PathBuf::from("/tmp/x"));
        assert_eq!(
            resource_dir("file://localhost/tmp/x"),
            PathBuf::from("/tmp/x")
        );
        assert_eq!(resource_dir("/plain/path"), PathBuf::from("/plain/path"));
        assert_eq!(resource_dir("file:///a%2"), PathBuf::from("/a%2"));
    }
}

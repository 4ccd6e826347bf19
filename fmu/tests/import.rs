//! The FMU as an importer sees it: exported by `vanefit::export::fmu::write_fmu`,
//! unpacked, its shared library loaded with `libloading` and driven through the FMI 2.0 C
//! functions (co-simulation and model exchange), its answers checked against the library's
//! own `MotorFmu` and against physics (a steady start is steady; a throttle at port 2 slows
//! the motor).

use libloading::{Library, Symbol};
use std::ffi::{c_char, c_int, c_uint, c_void, CString};
use std::path::{Path, PathBuf};
use vanefit::data::FitFile;
use vanefit::export::fmu::vr;
use vanefit::export::fmu::MotorFmu;
use vanefit::export::fmu::{find_binary, write_fmu};

type Instantiate = unsafe extern "C" fn(
    *const c_char,
    c_int,
    *const c_char,
    *const c_char,
    *const c_void,
    c_int,
    c_int,
) -> *mut c_void;
type Call = unsafe extern "C" fn(*mut c_void) -> c_int;
type Setup = unsafe extern "C" fn(*mut c_void, c_int, f64, f64, c_int, f64) -> c_int;
type RealIo = unsafe extern "C" fn(*mut c_void, *const c_uint, usize, *mut f64) -> c_int;
type DoStep = unsafe extern "C" fn(*mut c_void, f64, f64, c_int) -> c_int;
type States = unsafe extern "C" fn(*mut c_void, *mut f64, usize) -> c_int;
type Free = unsafe extern "C" fn(*mut c_void);

const FIT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../fits/ar034-synthetic.json");

/// The shared library cargo built beside this test's executable (`target/<profile>/`).
fn built_library() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    find_binary(None, Some(&exe)).expect("cargo builds the cdylib before its tests")
}

/// Exports the shipped fit and unpacks the FMU into `dir`; returns (library, resources
/// URI, GUID).
fn unpacked(dir: &Path) -> (PathBuf, String, String) {
    let fmu = dir.join("motor.fmu");
    let summary = write_fmu(Path::new(FIT), &built_library(), &fmu).unwrap();
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
    archive.extract(dir.join("unpacked")).unwrap();
    let root = dir.join("unpacked");
    let so = root.join("binaries/linux64/vanefit_fmu.so");
    let uri = format!("file://{}", root.join("resources").display());
    (so, uri, summary.guid)
}

struct Api<'l> {
    lib: &'l Library,
}

impl<'l> Api<'l> {
    fn get<T>(&self, name: &str) -> Symbol<'l, T> {
        // SAFETY: the FMI 2.0 signatures above match the exported functions.
        unsafe { self.lib.get(name.as_bytes()) }.unwrap_or_else(|e| panic!("{name}: {e}"))
    }

    fn instantiate(&self, kind: c_int, guid: &str, uri: &str) -> *mut c_void {
        let f: Symbol<Instantiate> = self.get("fmi2Instantiate");
        let (name, guid, uri) = (
            CString::new("motor").unwrap(),
            CString::new(guid).unwrap(),
            CString::new(uri).unwrap(),
        );
        // SAFETY: valid C strings; no callbacks (the FMU then logs nowhere).
        unsafe {
            f(
                name.as_ptr(),
                kind,
                guid.as_ptr(),
                uri.as_ptr(),
                std::ptr::null(),
                0,
                0,
            )
        }
    }

    fn call(&self, name: &str, c: *mut c_void) -> c_int {
        let f: Symbol<Call> = self.get(name);
        unsafe { f(c) }
    }

    fn init(&self, c: *mut c_void, inputs: &[(u32, f64)]) {
        let setup: Symbol<Setup> = self.get("fmi2SetupExperiment");
        assert_eq!(unsafe { setup(c, 0, 0.0, 0.0, 0, 0.0) }, 0);
        assert_eq!(self.call("fmi2EnterInitializationMode", c), 0);
        for &(r, v) in inputs {
            self.set(c, r, v);
        }
        assert_eq!(self.call("fmi2ExitInitializationMode", c), 0);
    }

    fn set(&self, c: *mut c_void, r: u32, v: f64) -> c_int {
        let f: Symbol<RealIo> = self.get("fmi2SetReal");
        let mut v = v;
        unsafe { f(c, &r, 1, &mut v) }
    }

    fn real(&self, c: *mut c_void, r: u32) -> f64 {
        let f: Symbol<RealIo> = self.get("fmi2GetReal");
        let mut v = f64::NAN;
        assert_eq!(unsafe { f(c, &r, 1, &mut v) }, 0);
        v
    }
}

#[test]
fn the_exported_fmu_loads_and_steps_through_the_fmi_functions() {
    let dir = tempfile::tempdir().unwrap();
    let (so, uri, guid) = unpacked(dir.path());
    // SAFETY: the library is the FMU's own binary; loading it runs no initialisers of note.
    let lib = unsafe { Library::new(&so) }.unwrap();
    let api = Api { lib: &lib };
    // A wrong GUID is refused: the description and the packed fit must belong together.
    assert!(api.instantiate(1, "{not-this-one}", &uri).is_null());

    // Co-simulation: a steady start under a viscous brake stays put; throttling port 2
    // slows the motor.
    let cs = api.instantiate(1, &guid, &uri);
    assert!(!cs.is_null());
    api.init(cs, &[(vr::P_SUPPLY, 6e5), (vr::C_BRAKE, 1e-4)]);
    let w0 = api.real(cs, vr::SPEED);
    let step: Symbol<DoStep> = api.get("fmi2DoStep");
    let mut t = 0.0;
    for _ in 0..10 {
        assert_eq!(unsafe { step(cs, t, 0.05, 1) }, 0);
        t += 0.05;
    }
    let w1 = api.real(cs, vr::SPEED);
    assert!(w0 > 100.0 && (w1 - w0).abs() < 1e-4 * w0, "{w0} → {w1}");
    // The same through the library directly: the FMU is the library's model.
    let mut direct = MotorFmu::new(FitFile::read(Path::new(FIT)).unwrap()).unwrap();
    direct.set_real(vr::P_SUPPLY, 6e5).unwrap();
    direct.set_real(vr::C_BRAKE, 1e-4).unwrap();
    direct.initialize().unwrap();
    assert_eq!(direct.x[3], w0);
    assert_eq!(api.set(cs, vr::C_THROTTLE2, 2e-9), 0);
    for _ in 0..20 {
        assert_eq!(unsafe { step(cs, t, 0.05, 1) }, 0);
        t += 0.05;
    }
    let w2 = api.real(cs, vr::SPEED);
    assert!(w2 < 0.9 * w1, "throttled {w2} vs free {w1}");
    // A negative pressure is refused with an error status, not a crash.
    assert_eq!(api.set(cs, vr::P_SUPPLY, -1.0), 3);
    let free: Symbol<Free> = api.get("fmi2FreeInstance");
    unsafe { free(cs) };

    // Model exchange: the derivatives at the steady start vanish, and equal the library's.
    let me = api.instantiate(0, &guid, &uri);
    assert!(!me.is_null());
    api.init(me, &[(vr::P_SUPPLY, 6e5), (vr::C_BRAKE, 1e-4)]);
    let get_x: Symbol<States> = api.get("fmi2GetContinuousStates");
    let get_dx: Symbol<States> = api.get("fmi2GetDerivatives");
    let (mut x, mut dx) = ([0.0; 4], [0.0; 4]);
    assert_eq!(unsafe { get_x(me, x.as_mut_ptr(), 4) }, 0);
    assert_eq!(unsafe { get_dx(me, dx.as_mut_ptr(), 4) }, 0);
    assert_eq!(x, direct.x);
    assert_eq!(dx, direct.derivatives());
    assert!(dx[3].abs() < 1e-2, "{dx:?}");
    assert_eq!(
        unsafe { get_x(me, x.as_mut_ptr(), 3) },
        3,
        "4 states, not 3"
    );
    unsafe { free(me) };
}

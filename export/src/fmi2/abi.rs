//! The FMI 2.0 C functions (model exchange and co-simulation in one library). Each converts its
//! pointers, runs the instance's method inside `catch_unwind` (a panic never crosses into the
//! importer: it becomes `fmi2Fatal`) and logs a refusal through the importer's logger.

use core::ffi::{c_char, c_int, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::instance::{Instance, Phase, Snapshot};
use super::types::*;
use crate::bundle_source;
use crate::plant::Loaded;

/// An instance with the importer's callbacks.
struct Component {
    instance: Instance,
    logger: Fmi2CallbackLogger,
    env: Fmi2ComponentEnvironment,
    logging_on: bool,
    /// The instance name as C text, for the logger.
    c_name: std::ffi::CString,
}

impl Component {
    fn log(&self, status: Fmi2Status, category: &str, message: &str) {
        if status == Fmi2Status::Ok && !self.logging_on {
            return;
        }
        log(
            self.logger,
            self.env,
            &self.c_name,
            status,
            category,
            message,
        );
    }
}

fn log(
    logger: Fmi2CallbackLogger,
    env: Fmi2ComponentEnvironment,
    name: &CStr,
    status: Fmi2Status,
    category: &str,
    message: &str,
) {
    let Some(logger) = logger else { return };
    let clean = |s: &str| std::ffi::CString::new(s.replace('\0', " ")).unwrap_or_default();
    let (category, message) = (clean(category), clean(message));
    // SAFETY: the importer's logger, called as the standard says, with "%s" and one string so
    // that a '%' in a message is not read as a format.
    unsafe {
        logger(
            env,
            name.as_ptr(),
            status as c_int,
            category.as_ptr(),
            c"%s".as_ptr(),
            message.as_ptr(),
        )
    };
}

/// Runs `body` on the component `c`, turning a refusal into `fmi2Error` (logged) and a panic
/// into `fmi2Fatal`.
fn with(
    c: Fmi2Component,
    function: &str,
    body: impl FnOnce(&mut Component) -> Result<Fmi2Status, String>,
) -> c_int {
    if c.is_null() {
        return Fmi2Status::Error as c_int;
    }
    // SAFETY: `c` came from `fmi2Instantiate` (a leaked `Box<Component>`) and is not freed.
    let component = unsafe { &mut *(c as *mut Component) };
    let result = catch_unwind(AssertUnwindSafe(|| body(component)));
    let status = match result {
        Ok(Ok(status)) => status,
        Ok(Err(why)) => {
            component.log(
                Fmi2Status::Error,
                "logStatusError",
                &format!("{function}: {why}"),
            );
            Fmi2Status::Error
        }
        Err(_) => {
            component.instance.phase = Phase::Stopped;
            component.log(
                Fmi2Status::Fatal,
                "logStatusFatal",
                &format!("{function}: panicked"),
            );
            Fmi2Status::Fatal
        }
    };
    status as c_int
}

/// A slice from a C array (empty for a null pointer or no entries).
///
/// # Safety
/// `ptr` must point to `n` values, or be null.
unsafe fn slice<'a, T>(ptr: *const T, n: usize) -> &'a [T] {
    if ptr.is_null() || n == 0 {
        &[]
    } else {
        std::slice::from_raw_parts(ptr, n)
    }
}

/// # Safety
/// `ptr` must point to `n` writable values, or be null.
unsafe fn slice_mut<'a, T>(ptr: *mut T, n: usize) -> &'a mut [T] {
    if ptr.is_null() || n == 0 {
        &mut []
    } else {
        std::slice::from_raw_parts_mut(ptr, n)
    }
}

/// # Safety
/// `s` must be null or a NUL-terminated string.
unsafe fn text(s: Fmi2String) -> String {
    if s.is_null() {
        String::new()
    } else {
        CStr::from_ptr(s).to_string_lossy().into_owned()
    }
}

fn ok() -> Result<Fmi2Status, String> {
    Ok(Fmi2Status::Ok)
}

#[no_mangle]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

#[no_mangle]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// # Safety
/// The arguments of `fmi2Instantiate` as the FMI 2.0 standard defines them.
#[no_mangle]
pub unsafe extern "C" fn fmi2Instantiate(
    instance_name: Fmi2String,
    fmu_type: c_int,
    guid: Fmi2String,
    resource_location: Fmi2String,
    functions: *const Fmi2CallbackFunctions,
    _visible: Fmi2Boolean,
    logging_on: Fmi2Boolean,
) -> Fmi2Component {
    let name = text(instance_name);
    let (logger, env) = match functions.as_ref() {
        Some(f) => (f.logger, f.component_environment),
        None => (None, std::ptr::null_mut()),
    };
    let c_name = std::ffi::CString::new(name.replace('\0', " ")).unwrap_or_default();
    let refuse = |why: String| {
        log(
            logger,
            env,
            &c_name,
            Fmi2Status::Error,
            "logStatusError",
            &why,
        );
        std::ptr::null_mut()
    };
    let (guid, location) = (text(guid), text(resource_location));
    let made = catch_unwind(AssertUnwindSafe(|| -> Result<Instance, String> {
        if fmu_type != FMI2_MODEL_EXCHANGE && fmu_type != FMI2_CO_SIMULATION {
            return Err(format!("fmi2Instantiate: fmuType {fmu_type} is not 0 or 1"));
        }
        let bundle = bundle_source::from_resources(&location)?;
        let expected = bundle.guid();
        if guid != expected {
            return Err(format!(
                "fmi2Instantiate: GUID {guid} is not this FMU's {expected} (modelDescription.xml \
                 and resources/ of different exports?)"
            ));
        }
        let model = Loaded::new(&bundle)?;
        Ok(Instance::new(model, fmu_type == FMI2_CO_SIMULATION))
    }));
    match made {
        Ok(Ok(instance)) => Box::into_raw(Box::new(Component {
            instance,
            logger,
            env,
            logging_on: logging_on != 0,
            c_name,
        })) as Fmi2Component,
        Ok(Err(why)) => refuse(why),
        Err(_) => refuse("fmi2Instantiate: panicked".into()),
    }
}

/// # Safety
/// `c` from `fmi2Instantiate`, not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeInstance(c: Fmi2Component) {
    if !c.is_null() {
        drop(Box::from_raw(c as *mut Component));
    }
}

/// # Safety
/// As the standard defines `fmi2SetDebugLogging`.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: Fmi2Component,
    logging_on: Fmi2Boolean,
    _n: usize,
    _categories: *const Fmi2String,
) -> c_int {
    with(c, "fmi2SetDebugLogging", |k| {
        k.logging_on = logging_on != 0;
        ok()
    })
}

/// # Safety
/// As the standard defines `fmi2SetupExperiment`.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetupExperiment(
    c: Fmi2Component,
    _tolerance_defined: Fmi2Boolean,
    _tolerance: Fmi2Real,
    start_time: Fmi2Real,
    _stop_time_defined: Fmi2Boolean,
    _stop_time: Fmi2Real,
) -> c_int {
    with(c, "fmi2SetupExperiment", |k| {
        if !start_time.is_finite() {
            return Err(format!("startTime {start_time} is not finite"));
        }
        k.instance.time = start_time;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterInitializationMode(c: Fmi2Component) -> c_int {
    with(c, "fmi2EnterInitializationMode", |k| {
        k.instance.phase = Phase::Initializing;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2ExitInitializationMode(c: Fmi2Component) -> c_int {
    with(c, "fmi2ExitInitializationMode", |k| {
        k.instance.phase = Phase::Running;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2Terminate(c: Fmi2Component) -> c_int {
    with(c, "fmi2Terminate", |k| {
        k.instance.phase = Phase::Stopped;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2Reset(c: Fmi2Component) -> c_int {
    with(c, "fmi2Reset", |k| {
        k.instance.reset();
        ok()
    })
}

/// # Safety
/// As the standard defines `fmi2GetReal`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetReal(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    nvr: usize,
    value: *mut Fmi2Real,
) -> c_int {
    with(c, "fmi2GetReal", |k| {
        k.instance.get_real(slice(vr, nvr), slice_mut(value, nvr))?;
        ok()
    })
}

/// # Safety
/// As the standard defines `fmi2SetReal`.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetReal(
    c: Fmi2Component,
    vr: *const Fmi2ValueReference,
    nvr: usize,
    value: *const Fmi2Real,
) -> c_int {
    with(c, "fmi2SetReal", |k| {
        k.instance.set_real(slice(vr, nvr), slice(value, nvr))?;
        ok()
    })
}

/// No variables of this type: any value reference is refused.
fn none_of_type(what: &str, nvr: usize) -> Result<Fmi2Status, String> {
    if nvr == 0 {
        ok()
    } else {
        Err(format!("the model has no {what} variables"))
    }
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetInteger(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *mut Fmi2Integer,
) -> c_int {
    with(c, "fmi2GetInteger", |_| none_of_type("Integer", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetInteger(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *const Fmi2Integer,
) -> c_int {
    with(c, "fmi2SetInteger", |_| none_of_type("Integer", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *mut Fmi2Boolean,
) -> c_int {
    with(c, "fmi2GetBoolean", |_| none_of_type("Boolean", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *const Fmi2Boolean,
) -> c_int {
    with(c, "fmi2SetBoolean", |_| none_of_type("Boolean", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetString(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *mut Fmi2String,
) -> c_int {
    with(c, "fmi2GetString", |_| none_of_type("String", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetString(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _value: *const Fmi2String,
) -> c_int {
    with(c, "fmi2SetString", |_| none_of_type("String", nvr))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetFMUstate(c: Fmi2Component, state: *mut Fmi2FmuState) -> c_int {
    with(c, "fmi2GetFMUstate", |k| {
        let Some(slot) = state.as_mut() else {
            return Err("FMUstate is a null pointer".into());
        };
        let snapshot = k.instance.snapshot();
        if slot.is_null() {
            *slot = Box::into_raw(Box::new(snapshot)) as Fmi2FmuState;
        } else {
            *(*slot as *mut Snapshot) = snapshot;
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetFMUstate(c: Fmi2Component, state: Fmi2FmuState) -> c_int {
    with(c, "fmi2SetFMUstate", |k| {
        let Some(s) = (state as *const Snapshot).as_ref() else {
            return Err("FMUstate is a null pointer".into());
        };
        k.instance.restore(s)?;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2FreeFMUstate(c: Fmi2Component, state: *mut Fmi2FmuState) -> c_int {
    with(c, "fmi2FreeFMUstate", |_| {
        if let Some(slot) = state.as_mut() {
            if !slot.is_null() {
                drop(Box::from_raw(*slot as *mut Snapshot));
                *slot = std::ptr::null_mut();
            }
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: Fmi2Component,
    state: Fmi2FmuState,
    size: *mut usize,
) -> c_int {
    with(c, "fmi2SerializedFMUstateSize", |_| {
        let (Some(s), Some(size)) = ((state as *const Snapshot).as_ref(), size.as_mut()) else {
            return Err("null pointer".into());
        };
        *size = s.to_bytes().len();
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: Fmi2Component,
    state: Fmi2FmuState,
    bytes: *mut Fmi2Byte,
    size: usize,
) -> c_int {
    with(c, "fmi2SerializeFMUstate", |_| {
        let Some(s) = (state as *const Snapshot).as_ref() else {
            return Err("FMUstate is a null pointer".into());
        };
        let data = s.to_bytes();
        if size != data.len() {
            return Err(format!("{size} bytes given, the state has {}", data.len()));
        }
        let out = slice_mut(bytes as *mut u8, size);
        out.copy_from_slice(&data);
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: Fmi2Component,
    bytes: *const Fmi2Byte,
    size: usize,
    state: *mut Fmi2FmuState,
) -> c_int {
    with(c, "fmi2DeSerializeFMUstate", |k| {
        let (nx, nu, np) = k.instance.sizes();
        let Some(s) = Snapshot::from_bytes(slice(bytes as *const u8, size), nx, nu, np) else {
            return Err(format!("{size} bytes are not a state of this model"));
        };
        let Some(slot) = state.as_mut() else {
            return Err("FMUstate is a null pointer".into());
        };
        *slot = Box::into_raw(Box::new(s)) as Fmi2FmuState;
        ok()
    })
}

/// # Safety
/// As the standard defines `fmi2GetDirectionalDerivative`.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: Fmi2Component,
    unknown: *const Fmi2ValueReference,
    n_unknown: usize,
    known: *const Fmi2ValueReference,
    n_known: usize,
    dv_known: *const Fmi2Real,
    dv_unknown: *mut Fmi2Real,
) -> c_int {
    with(c, "fmi2GetDirectionalDerivative", |k| {
        k.instance.directional_derivative(
            slice(unknown, n_unknown),
            slice(known, n_known),
            slice(dv_known, n_known),
            slice_mut(dv_unknown, n_unknown),
        )?;
        ok()
    })
}

// ---- model exchange ----

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterEventMode(c: Fmi2Component) -> c_int {
    with(c, "fmi2EnterEventMode", |_| ok())
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: Fmi2Component,
    info: *mut Fmi2EventInfo,
) -> c_int {
    with(c, "fmi2NewDiscreteStates", |_| {
        if let Some(info) = info.as_mut() {
            *info = Fmi2EventInfo {
                new_discrete_states_needed: 0,
                terminate_simulation: 0,
                nominals_of_continuous_states_changed: 0,
                values_of_continuous_states_changed: 0,
                next_event_time_defined: 0,
                next_event_time: 0.0,
            };
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(c: Fmi2Component) -> c_int {
    with(c, "fmi2EnterContinuousTimeMode", |_| ok())
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: Fmi2Component,
    _no_set_prior: Fmi2Boolean,
    enter_event_mode: *mut Fmi2Boolean,
    terminate: *mut Fmi2Boolean,
) -> c_int {
    with(c, "fmi2CompletedIntegratorStep", |_| {
        if let Some(e) = enter_event_mode.as_mut() {
            *e = 0;
        }
        if let Some(t) = terminate.as_mut() {
            *t = 0;
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetTime(c: Fmi2Component, time: Fmi2Real) -> c_int {
    with(c, "fmi2SetTime", |k| {
        k.instance.time = time;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: Fmi2Component,
    x: *const Fmi2Real,
    nx: usize,
) -> c_int {
    with(c, "fmi2SetContinuousStates", |k| {
        k.instance.set_states(slice(x, nx))?;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: Fmi2Component,
    x: *mut Fmi2Real,
    nx: usize,
) -> c_int {
    with(c, "fmi2GetContinuousStates", |k| {
        let out = slice_mut(x, nx);
        if out.len() != k.instance.nx() {
            return Err(format!(
                "{nx} states asked for, the model has {}",
                k.instance.nx()
            ));
        }
        out.copy_from_slice(&k.instance.x);
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: Fmi2Component,
    dx: *mut Fmi2Real,
    nx: usize,
) -> c_int {
    with(c, "fmi2GetDerivatives", |k| {
        k.instance.get_derivatives(slice_mut(dx, nx))?;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: Fmi2Component,
    _z: *mut Fmi2Real,
    ni: usize,
) -> c_int {
    with(c, "fmi2GetEventIndicators", |_| {
        none_of_type("event indicator", ni)
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: Fmi2Component,
    nominals: *mut Fmi2Real,
    nx: usize,
) -> c_int {
    with(c, "fmi2GetNominalsOfContinuousStates", |_| {
        slice_mut(nominals, nx).fill(1.0);
        ok()
    })
}

// ---- co-simulation ----

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _order: *const Fmi2Integer,
    _value: *const Fmi2Real,
) -> c_int {
    with(c, "fmi2SetRealInputDerivatives", |_| {
        none_of_type("interpolated input (canInterpolateInputs is false)", nvr)
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
    c: Fmi2Component,
    _vr: *const Fmi2ValueReference,
    nvr: usize,
    _order: *const Fmi2Integer,
    _value: *mut Fmi2Real,
) -> c_int {
    with(c, "fmi2GetRealOutputDerivatives", |_| {
        none_of_type("output derivative (maxOutputDerivativeOrder is 0)", nvr)
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2DoStep(
    c: Fmi2Component,
    t: Fmi2Real,
    h: Fmi2Real,
    _no_set_prior: Fmi2Boolean,
) -> c_int {
    with(c, "fmi2DoStep", |k| {
        if !k.instance.co_simulation {
            return Err("the instance is for model exchange".into());
        }
        k.instance.do_step(t, h)?;
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2CancelStep(c: Fmi2Component) -> c_int {
    with(c, "fmi2CancelStep", |_| {
        Err("steps are not asynchronous: there is nothing to cancel".into())
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStatus(c: Fmi2Component, kind: c_int, value: *mut c_int) -> c_int {
    with(c, "fmi2GetStatus", |_| {
        if kind != FMI2_DO_STEP_STATUS {
            return Ok(Fmi2Status::Discard);
        }
        if let Some(v) = value.as_mut() {
            *v = Fmi2Status::Ok as c_int;
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: Fmi2Component,
    kind: c_int,
    value: *mut Fmi2Real,
) -> c_int {
    with(c, "fmi2GetRealStatus", |k| {
        if kind != FMI2_LAST_SUCCESSFUL_TIME {
            return Ok(Fmi2Status::Discard);
        }
        if let Some(v) = value.as_mut() {
            *v = k.instance.time;
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: Fmi2Component,
    _kind: c_int,
    _value: *mut Fmi2Integer,
) -> c_int {
    with(c, "fmi2GetIntegerStatus", |_| Ok(Fmi2Status::Discard))
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: Fmi2Component,
    kind: c_int,
    value: *mut Fmi2Boolean,
) -> c_int {
    with(c, "fmi2GetBooleanStatus", |k| {
        if kind != FMI2_TERMINATED {
            return Ok(Fmi2Status::Discard);
        }
        if let Some(v) = value.as_mut() {
            *v = c_int::from(k.instance.phase == Phase::Stopped);
        }
        ok()
    })
}

/// # Safety
/// As the standard defines it.
#[no_mangle]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: Fmi2Component,
    _kind: c_int,
    _value: *mut Fmi2String,
) -> c_int {
    with(c, "fmi2GetStringStatus", |_| Ok(Fmi2Status::Discard))
}

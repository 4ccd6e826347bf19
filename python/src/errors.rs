//! The package's exceptions: `VanefitError`, and under it `DataError` (a file or dataset that
//! cannot be read or used, with the same located message as the command line) and
//! `ParameterError` (a bad option, parameter name or value).

use pyo3::prelude::*;

pyo3::create_exception!(
    _core,
    VanefitError,
    pyo3::exceptions::PyException,
    "Anything vanefit refuses or fails at."
);
pyo3::create_exception!(
    _core,
    DataError,
    VanefitError,
    "A dataset, recording or fit file that cannot be read or used; the message names the file, line and column."
);
pyo3::create_exception!(
    _core,
    ParameterError,
    VanefitError,
    "A bad option, parameter name or parameter value; the message names it."
);

/// A data error as `DataError`, with its `Display` text (what the command line prints).
pub fn data_err(e: impl std::fmt::Display) -> PyErr {
    DataError::new_err(e.to_string())
}

/// A parameter error as `ParameterError`, with its `Display` text.
pub fn param_err(e: impl std::fmt::Display) -> PyErr {
    ParameterError::new_err(e.to_string())
}

/// Adds the exceptions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("VanefitError", py.get_type::<VanefitError>())?;
    m.add("DataError", py.get_type::<DataError>())?;
    m.add("ParameterError", py.get_type::<ParameterError>())?;
    Ok(())
}

//! Checks of NumPy array arguments whose messages say what is wrong: not an
//! array at all, the dtype (named), the number of dimensions, the length of
//! the last axis, the byte order, points whose memory is not aligned, and
//! (where the data are read as one slice) arrays that are not contiguous.
//! Every problem found is listed, each with what was expected.

use crate::errors;
use numpy::npyffi::flags::NPY_ARRAY_ALIGNED;
use numpy::{
    Element, PyArray1, PyArrayDescr, PyArrayDescrMethods, PyArrayMethods, PyReadonlyArray1,
    PyUntypedArray, PyUntypedArrayMethods,
};
use pyo3::prelude::*;

/// A shape as Python prints it: `(2, 3, 4)`, `(5,)`, `()`.
pub fn py_shape(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let s: Vec<String> = shape.iter().map(|n| n.to_string()).collect();
            format!("({})", s.join(", "))
        }
    }
}

/// `obj` as an array, or an error naming what it is instead.
fn untyped<'a, 'py>(
    obj: &'a Bound<'py, PyAny>,
    what: &str,
    expected: &str,
) -> PyResult<&'a Bound<'py, PyUntypedArray>> {
    obj.downcast::<PyUntypedArray>().map_err(|_| {
        let t = obj
            .get_type()
            .name()
            .map(|n| n.to_string())
            .unwrap_or_else(|_| "?".into());
        errors::input(format!(
            "{what}: a {t}, expected a NumPy array ({expected})"
        ))
    })
}

fn aligned(a: &Bound<'_, PyUntypedArray>) -> bool {
    // SAFETY: `a` is a live NumPy array; only its flags word is read.
    unsafe { (*a.as_array_ptr()).flags & NPY_ARRAY_ALIGNED != 0 }
}

/// What is wrong with dtype `d` where `want` (float32, float64, ...) is
/// expected, or None when it is one of them.
fn dtype_problem(d: &Bound<'_, PyArrayDescr>, want: &[Bound<'_, PyArrayDescr>]) -> Option<String> {
    if want.iter().any(|w| d.is_equiv_to(w)) {
        return None;
    }
    let names: Vec<String> = want.iter().map(|w| w.to_string()).collect();
    let names = names.join(" or ");
    // The same type in the other byte order (data from a big-endian file).
    let swapped = want.iter().find(|w| {
        d.kind() == w.kind()
            && d.itemsize() == w.itemsize()
            && d.is_native_byteorder() == Some(false)
    });
    Some(match swapped {
        Some(w) => format!(
            "dtype {d} is {w} in non-native byte order, expected native {names} (convert with .astype(np.{w}))"
        ),
        None => format!("dtype {d}, expected {names}"),
    })
}

/// Checks that `obj` is an `N x 3` array of (native, aligned) float32 or
/// float64, in any memory layout; the error lists every problem.
pub fn check_points(py: Python<'_>, obj: &Bound<'_, PyAny>) -> PyResult<()> {
    let expected = "N x 3, float32 or float64";
    let a = untyped(obj, "points", expected)?;
    let mut problems = Vec::new();
    let want = [numpy::dtype::<f32>(py), numpy::dtype::<f64>(py)];
    if let Some(p) = dtype_problem(&a.dtype(), &want) {
        problems.push(p);
    }
    let shape = a.shape();
    if shape.len() != 2 {
        let mut p = format!(
            "{} dimension{} (shape {}), expected 2 (an N x 3 array, one row per point)",
            shape.len(),
            if shape.len() == 1 { "" } else { "s" },
            py_shape(shape)
        );
        if shape.len() == 1 && shape[0] % 3 == 0 && shape[0] > 3 {
            p.push_str(": .reshape(-1, 3) makes rows of x, y, z");
        }
        problems.push(p);
    } else if shape[1] != 3 {
        let mut p = format!(
            "last axis of length {} (shape {}), expected 3 (x, y, z)",
            shape[1],
            py_shape(shape)
        );
        if shape[0] == 3 {
            p.push_str(": a 3 x N array? pass its transpose, points.T");
        }
        problems.push(p);
    }
    if !aligned(a) {
        problems.push(
            "data not aligned in memory, expected an aligned array (copy it with np.array(points))"
                .into(),
        );
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(errors::input(format!("points: {}", problems.join("; "))))
    }
}

/// `obj` as a one-dimensional contiguous array of `T` (copied if its data
/// are not aligned), or an error listing what is wrong (`what` names the
/// argument).
pub fn vector<'py, T: Element>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    what: &str,
) -> PyResult<PyReadonlyArray1<'py, T>> {
    let want = numpy::dtype::<T>(py);
    let a = untyped(obj, what, &format!("one-dimensional, {want}"))?;
    let mut problems = Vec::new();
    if let Some(p) = dtype_problem(&a.dtype(), std::slice::from_ref(&want)) {
        problems.push(p);
    }
    if a.ndim() != 1 {
        problems.push(format!(
            "{} dimensions (shape {}), expected 1",
            a.ndim(),
            py_shape(a.shape())
        ));
    } else if !a.is_contiguous() {
        problems.push(format!(
            "not contiguous (strides {:?} bytes), expected a contiguous array (np.ascontiguousarray({what}))",
            a.strides()
        ));
    }
    if !problems.is_empty() {
        return Err(errors::input(format!("{what}: {}", problems.join("; "))));
    }
    let typed = obj
        .downcast::<PyArray1<T>>()
        .map_err(|e| errors::input(format!("{what}: {e}")))?;
    // Unpickled arrays (protocol 5 buffers from a Dask worker) may sit at
    // any byte offset: those are read from an aligned copy.
    let typed = if aligned(a) {
        typed.clone()
    } else {
        typed.call_method0("copy")?.downcast_into::<PyArray1<T>>()?
    };
    typed
        .try_readonly()
        .map_err(|e| errors::input(format!("{what}: {e}")))
}

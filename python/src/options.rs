//! Keyword options: the command line's strategy options under the same names, `-` spelled `_`
//! (`--cone-weight` is `cone_weight=`), checked as the command line checks them.

use crate::errors::{fail, Kind, Result};
use meshletlab::meshlet::order::MeshletOrder;
use meshletlab::strategy::kmedoids::Grow;
use meshletlab::strategy::Options;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::Duration;

/// Every strategy option, in the command line's order.
pub const NAMES: [&str; 11] = [
    "cone_weight",
    "cache_size",
    "fill_weight",
    "kmedoids_iterations",
    "kmedoids_threshold",
    "kmedoids_grow",
    "kmedoids_regions",
    "kmedoids_moves",
    "paper_budget",
    "local_order",
    "meshlet_order",
];

/// A value of the wrong type or range for option `name`.
fn bad(name: &str, want: &str, v: &Bound<'_, PyAny>) -> crate::errors::Fail {
    let shown = v.repr().map(|r| r.to_string()).unwrap_or_default();
    fail(Kind::Option, format!("{name} must be {want}, not {shown}"))
}

fn number(name: &str, v: &Bound<'_, PyAny>, want: &str, ok: impl Fn(f64) -> bool) -> Result<f64> {
    // A bool is an int in Python; as a weight or a threshold it is a mistake.
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(bad(name, want, v));
    }
    match v.extract::<f64>() {
        Ok(x) if ok(x) => Ok(x),
        _ => Err(bad(name, want, v)),
    }
}

fn count(name: &str, v: &Bound<'_, PyAny>, min: u32, max: u32) -> Result<u32> {
    let want = format!("an integer in {min}..={max}");
    if v.is_instance_of::<pyo3::types::PyBool>() {
        return Err(bad(name, &want, v));
    }
    match v.extract::<u32>() {
        Ok(x) if (min..=max).contains(&x) => Ok(x),
        _ => Err(bad(name, &want, v)),
    }
}

fn text<T: std::str::FromStr<Err = String>>(name: &str, v: &Bound<'_, PyAny>) -> Result<T> {
    let s: String = v.extract().map_err(|_| bad(name, "a string", v))?;
    s.parse()
        .map_err(|e: String| fail(Kind::Option, format!("{name}: {e}")))
}

/// The options in `kwargs`, defaults elsewhere; `func` names the call in the error for a keyword
/// that is no option.
pub fn parse(func: &str, kwargs: Option<&Bound<'_, PyDict>>) -> Result<Options> {
    let mut o = Options::default();
    let Some(kwargs) = kwargs else {
        return Ok(o);
    };
    for (k, v) in kwargs.iter() {
        let name: String = k.extract().unwrap_or_default();
        let kd = &mut o.kmedoids;
        match name.as_str() {
            "cone_weight" => {
                o.cone_weight =
                    number(&name, &v, "a number in 0..=1", |x| (0.0..=1.0).contains(&x))? as f32
            }
            "cache_size" => o.cache_size = count(&name, &v, 1, 256)?,
            "fill_weight" => {
                o.fill_weight = number(&name, &v, "a finite number >= 0 (an f32)", |x| {
                    x.is_finite() && x >= 0.0 && x <= f32::MAX as f64
                })? as f32
            }
            "kmedoids_iterations" => {
                let n = count(&name, &v, 0, u32::MAX)?;
                kd.sequential.max_rounds = n;
                kd.flat.max_iterations = n;
            }
            "kmedoids_threshold" => {
                kd.flat.shift_threshold = number(&name, &v, "a finite number >= 0", |x| {
                    x.is_finite() && x >= 0.0
                })?
            }
            "kmedoids_grow" => kd.sequential.grow = text::<Grow>(&name, &v)?,
            "kmedoids_regions" => kd.parallel.region_triangles = count(&name, &v, 1, u32::MAX)?,
            "kmedoids_moves" => kd.parallel.move_rounds = count(&name, &v, 0, u32::MAX)?,
            "paper_budget" => {
                let s = number(&name, &v, "a positive number of seconds", |x| {
                    x.is_finite() && x > 0.0 && Duration::try_from_secs_f64(x).is_ok()
                })?;
                kd.paper.budget = Duration::from_secs_f64(s);
            }
            "local_order" => {
                o.local_order = v
                    .extract::<bool>()
                    .map_err(|_| bad(&name, "True or False", &v))?
            }
            "meshlet_order" => o.meshlet_order = text::<MeshletOrder>(&name, &v)?,
            _ => {
                return Err(fail(
                    Kind::Option,
                    format!(
                    "{func}() got an unexpected keyword argument '{name}' (strategy options: {})",
                    NAMES.join(", ")
                ),
                ))
            }
        }
    }
    Ok(o)
}

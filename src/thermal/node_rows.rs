//! Values per owned node from values per thermal row when an owned node's
//! row may be another rank's (a copy of a split jointed body tied to a
//! lower copy there, [`Part::rows_across`], issue 19): those rows are
//! gathered through a PETSc scatter ([`crate::petsc::Gather`]).
//! Collective when `rows_across`, local otherwise.

use crate::parallel::Part;
use crate::petsc::{Gather, Result, Vector};

/// Collective when [`Part::rows_across`]. The value of every owned node
/// of `part` (part order) from the distributed vector `v` over its rows.
pub fn node_values(part: &Part, v: &Vector) -> Result<Vec<f64>> {
    let rows = v.to_local_vec()?;
    if !part.rows_across {
        return Ok(part.rows_to_nodes(&rows));
    }
    let mut g = Gather::new(v, &part.remote_rows())?;
    let remote = g.gather(v)?;
    Ok(part.rows_to_nodes_with(&rows, &remote))
}

/// Collective when [`Part::rows_across`]. The value of every owned node
/// of `part` from `rows`, one per owned row, of a vector laid out like
/// `like`.
pub fn nodes_from_rows(part: &Part, like: &Vector, rows: &[f64]) -> Result<Vec<f64>> {
    if !part.rows_across {
        return Ok(part.rows_to_nodes(rows));
    }
    let mut v = Vector::new_like(like, rows.len())?;
    v.view_mut()?.copy_from_slice(rows);
    node_values(part, &v)
}

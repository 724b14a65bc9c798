//! Geometric partitioning by recursive coordinate bisection, through
//! Zoltan (Sandia's load-balancing library, Debian's Trilinos build): the
//! objects (whole particles, or the elements of a large body) are cut by
//! planes into parts of equal weight, so objects near each other share a
//! rank. Used for the first distribution of the bodies and to follow them
//! as they move (repartitioning).
//!
//! Collective over the communicator.

use std::ffi::CString;
use std::os::raw::{c_int, c_void};
use std::sync::Once;

use mpi::traits::*;
use zoltan_sys as z;

/// One object to place: its weight (work) and its position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Object {
    /// Weight (> 0).
    pub weight: f64,
    /// A representative point (a centroid).
    pub point: [f64; 3],
}

static INIT: Once = Once::new();

/// What the callbacks read.
struct Data<'a> {
    objects: &'a [Object],
}

unsafe extern "C" fn num_obj(data: *mut c_void, ierr: *mut c_int) -> c_int {
    // SAFETY: `data` is the `Data` passed to the Zoltan_Set_*_Fn calls
    // below, alive for the whole Zoltan_LB_Partition call.
    let d = unsafe { &*(data as *const Data) };
    unsafe { *ierr = 0 };
    d.objects.len() as c_int
}

unsafe extern "C" fn obj_list(
    data: *mut c_void,
    _ngid: c_int,
    _nlid: c_int,
    gids: z::ZOLTAN_ID_PTR,
    lids: z::ZOLTAN_ID_PTR,
    wdim: c_int,
    wgts: *mut f32,
    ierr: *mut c_int,
) {
    // SAFETY: as in `num_obj`; Zoltan sized the arrays for the count that
    // `num_obj` returned (one id each, `wdim` weights each).
    let d = unsafe { &*(data as *const Data) };
    for (i, o) in d.objects.iter().enumerate() {
        unsafe {
            *gids.add(i) = i as z::ZOLTAN_ID_TYPE;
            *lids.add(i) = i as z::ZOLTAN_ID_TYPE;
            if wdim > 0 {
                *wgts.add(i) = o.weight.max(1e-30) as f32;
            }
        }
    }
    unsafe { *ierr = 0 };
}

unsafe extern "C" fn num_geom(_data: *mut c_void, ierr: *mut c_int) -> c_int {
    // SAFETY: Zoltan passes a valid error pointer.
    unsafe { *ierr = 0 };
    3
}

unsafe extern "C" fn geom_multi(
    data: *mut c_void,
    _ngid: c_int,
    _nlid: c_int,
    num_obj: c_int,
    _gids: z::ZOLTAN_ID_PTR,
    lids: z::ZOLTAN_ID_PTR,
    num_dim: c_int,
    geom: *mut f64,
    ierr: *mut c_int,
) {
    // SAFETY: as in `obj_list`; `geom` holds num_obj × num_dim values and
    // the local ids are those `obj_list` gave.
    let d = unsafe { &*(data as *const Data) };
    for i in 0..num_obj as usize {
        let o = &d.objects[unsafe { *lids.add(i) } as usize];
        for k in 0..num_dim as usize {
            unsafe { *geom.add(i * num_dim as usize + k) = o.point[k] };
        }
    }
    unsafe { *ierr = 0 };
}

/// A Zoltan structure, destroyed on drop.
struct Zoltan(*mut z::Zoltan_Struct);

impl Drop for Zoltan {
    fn drop(&mut self) {
        // SAFETY: self.0 came from Zoltan_Create and is destroyed once.
        unsafe { z::Zoltan_Destroy(&mut self.0) };
    }
}

/// How much of its height along gravity an object's point keeps for the
/// cuts ([`level`]).
pub(crate) const HEIGHT_SHARE: f64 = 0.1;

/// Under gravity `g`, shrink the objects' heights along it to
/// [`HEIGHT_SHARE`] of themselves, so that the bisection cuts across the
/// floor (by planes along gravity) unless the objects are ten times taller
/// than wide: a settling packing's contacts, which gather at the bottom,
/// then fall to every rank alike, and bodies falling straight down stay
/// on their rank. The cut is any partition (results do not depend on it).
pub fn level(objects: &mut [Object], g: [f64; 3]) {
    let len = g.iter().map(|c| c * c).sum::<f64>().sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return;
    }
    let n = g.map(|c| c / len);
    for o in objects {
        let h = (0..3).map(|d| o.point[d] * n[d]).sum::<f64>();
        for (p, nd) in o.point.iter_mut().zip(n) {
            *p -= (1.0 - HEIGHT_SHARE) * h * nd;
        }
    }
}

/// Collective. The rank each of this rank's `objects` goes to: recursive
/// coordinate bisection of all ranks' objects into as many parts as ranks,
/// of equal weight to within `imbalance` (max/mean, e.g. 1.05).
pub fn rcb<C: Communicator + AsRaw<Raw = mpi_sys::MPI_Comm>>(
    comm: &C,
    objects: &[Object],
    imbalance: f64,
) -> Result<Vec<u32>, String> {
    let size = comm.size();
    if size == 1 {
        return Ok(vec![0; objects.len()]);
    }
    // Fewer objects than ranks (Zoltan's RCB refuses them): object k in
    // global order goes to rank k, and the other ranks stay empty.
    let count = objects.len() as u64;
    let mut total = 0u64;
    comm.all_reduce_into(&count, &mut total, mpi::collective::SystemOperation::sum());
    if total < size as u64 {
        let mut before = 0u64;
        comm.exclusive_scan_into(&count, &mut before, mpi::collective::SystemOperation::sum());
        if comm.rank() == 0 {
            before = 0;
        }
        return Ok((0..count).map(|i| (before + i) as u32).collect());
    }
    INIT.call_once(|| {
        let mut ver = 0f32;
        // SAFETY: MPI is initialised (the communicator exists); Zoltan
        // reads no arguments here.
        unsafe { z::Zoltan_Initialize(0, std::ptr::null_mut(), &mut ver) };
    });
    // SAFETY: the raw communicator is valid for the call; Zoltan keeps a
    // duplicate.
    let zz = Zoltan(unsafe { z::Zoltan_Create(comm.as_raw()) });
    if zz.0.is_null() {
        return Err("Zoltan_Create failed".into());
    }
    let params = [
        ("DEBUG_LEVEL", "0".to_string()),
        ("LB_METHOD", "RCB".to_string()),
        ("NUM_GID_ENTRIES", "1".to_string()),
        ("NUM_LID_ENTRIES", "1".to_string()),
        ("OBJ_WEIGHT_DIM", "1".to_string()),
        ("RETURN_LISTS", "PARTITION ASSIGNMENTS".to_string()),
        ("IMBALANCE_TOL", format!("{imbalance}")),
        ("RCB_OUTPUT_LEVEL", "0".to_string()),
        ("RCB_RECTILINEAR_BLOCKS", "0".to_string()),
    ];
    for (k, v) in params {
        let (k, v) = (CString::new(k).unwrap(), CString::new(v).unwrap());
        // SAFETY: zz is valid; both strings are NUL-terminated.
        if unsafe { z::Zoltan_Set_Param(zz.0, k.as_ptr(), v.as_ptr()) } != 0 {
            return Err(format!("Zoltan_Set_Param {:?} failed", k));
        }
    }
    let mut data = Data { objects };
    let dp = &mut data as *mut Data as *mut c_void;
    // SAFETY: the callbacks match Zoltan's signatures; `data` outlives the
    // partition call below.
    unsafe {
        z::Zoltan_Set_Num_Obj_Fn(zz.0, Some(num_obj), dp);
        z::Zoltan_Set_Obj_List_Fn(zz.0, Some(obj_list), dp);
        z::Zoltan_Set_Num_Geom_Fn(zz.0, Some(num_geom), dp);
        z::Zoltan_Set_Geom_Multi_Fn(zz.0, Some(geom_multi), dp);
    }
    let (mut changes, mut ngid, mut nlid) = (0, 0, 0);
    let (mut nimp, mut nexp) = (0, 0);
    let mut imp_g: z::ZOLTAN_ID_PTR = std::ptr::null_mut();
    let mut imp_l: z::ZOLTAN_ID_PTR = std::ptr::null_mut();
    let mut imp_p: *mut c_int = std::ptr::null_mut();
    let mut imp_t: *mut c_int = std::ptr::null_mut();
    let mut exp_g: z::ZOLTAN_ID_PTR = std::ptr::null_mut();
    let mut exp_l: z::ZOLTAN_ID_PTR = std::ptr::null_mut();
    let mut exp_p: *mut c_int = std::ptr::null_mut();
    let mut exp_t: *mut c_int = std::ptr::null_mut();
    // SAFETY: every out-pointer is valid; Zoltan allocates the lists,
    // freed below with Zoltan_LB_Free_Part.
    let rc = unsafe {
        z::Zoltan_LB_Partition(
            zz.0,
            &mut changes,
            &mut ngid,
            &mut nlid,
            &mut nimp,
            &mut imp_g,
            &mut imp_l,
            &mut imp_p,
            &mut imp_t,
            &mut nexp,
            &mut exp_g,
            &mut exp_l,
            &mut exp_p,
            &mut exp_t,
        )
    };
    let me = comm.rank() as u32;
    let mut part = vec![me; objects.len()];
    if rc == 0 {
        for i in 0..nexp.max(0) as usize {
            // SAFETY: Zoltan returned nexp entries in each export list.
            let (lid, to) = unsafe { (*exp_l.add(i), *exp_t.add(i)) };
            if let Some(p) = part.get_mut(lid as usize) {
                *p = to as u32;
            }
        }
    }
    // SAFETY: the lists came from Zoltan_LB_Partition.
    unsafe {
        z::Zoltan_LB_Free_Part(&mut imp_g, &mut imp_l, &mut imp_p, &mut imp_t);
        z::Zoltan_LB_Free_Part(&mut exp_g, &mut exp_l, &mut exp_p, &mut exp_t);
    }
    // ZOLTAN_OK = 0, ZOLTAN_WARN = 1: both give a usable partition.
    if rc != 0 && rc != 1 {
        return Err(format!("Zoltan RCB failed (code {rc})"));
    }
    if part.iter().any(|&p| p >= size as u32) {
        return Err("Zoltan RCB returned a part beyond the ranks".into());
    }
    Ok(part)
}

//! Generates raw bindings to PETSc with bindgen.
//!
//! PETSc is found with pkg-config (`PETSc`). The build fails with a clear
//! message unless PETSc is configured with real double scalars and 32-bit
//! `PetscInt`, which the safe layer in `fdem::petsc` assumes. PETSc's view of
//! MPI is block-listed: the MPI types come from `mpi-sys`, so an rsmpi
//! communicator passes straight to PETSc.

use std::env;
use std::path::PathBuf;
use std::process::Command;

fn fail(msg: &str) -> ! {
    eprintln!("error: petsc-sys: {msg}");
    panic!("petsc-sys: {msg}");
}

fn mpi_include_dirs() -> Vec<PathBuf> {
    // Open MPI's wrapper knows its include path; fall back to pkg-config.
    if let Ok(out) = Command::new("mpicc").arg("--showme:incdirs").output() {
        if out.status.success() {
            let dirs: Vec<PathBuf> = String::from_utf8_lossy(&out.stdout)
                .split_whitespace()
                .map(PathBuf::from)
                .collect();
            if !dirs.is_empty() {
                return dirs;
            }
        }
    }
    match pkg_config::Config::new()
        .cargo_metadata(false)
        .probe("ompi")
    {
        Ok(lib) => lib.include_paths,
        Err(_) => Vec::new(),
    }
}

fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=PKG_CONFIG_PATH");

    let petsc = pkg_config::Config::new()
        .atleast_version("3.18")
        .probe("PETSc")
        .unwrap_or_else(|e| {
            fail(&format!(
                "PETSc >= 3.18 not found with pkg-config `PETSc` ({e}). \
                 Install Debian's petsc-dev (scripts/setup.sh does)."
            ))
        });

    // Check the scalar and index configuration in petscconf.h.
    let mut conf = None;
    for inc in &petsc.include_paths {
        let p = inc.join("petscconf.h");
        if p.exists() {
            conf = Some(std::fs::read_to_string(&p).unwrap_or_default());
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
    let conf = conf.unwrap_or_else(|| fail("petscconf.h not found in PETSc's include paths"));
    let has = |m: &str| {
        conf.lines()
            .any(|l| l.trim_start().starts_with(&format!("#define {m} ")))
    };
    if !has("PETSC_USE_REAL_DOUBLE") || has("PETSC_USE_COMPLEX") {
        fail("this PETSc is not configured with real double scalars (PETSC_USE_REAL_DOUBLE); fdem needs PetscScalar = f64");
    }
    if has("PETSC_USE_64BIT_INDICES") {
        fail(
            "this PETSc uses 64-bit indices (PETSC_USE_64BIT_INDICES); fdem needs 32-bit PetscInt",
        );
    }

    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .allowlist_function("(Petsc|Vec|Mat|KSP|PC|IS|ISLocalToGlobalMapping|SNES).*")
        .allowlist_type("(Petsc|_p_|Vec|Mat|KSP|PC|IS|Insert|Norm|Scatter|SNES).*")
        .allowlist_var("(PETSC|KSP|PC|MAT|VEC|NORM|INSERT|ADD|SNES)_.*")
        .blocklist_item("MPI_.*")
        .blocklist_item("ompi_.*")
        .blocklist_item("FP_.*")
        .blocklist_type("PetscSizeT")
        .default_enum_style(bindgen::EnumVariation::Rust {
            non_exhaustive: false,
        })
        .layout_tests(false)
        .generate_comments(false)
        .derive_default(true);
    for inc in petsc.include_paths.iter().chain(mpi_include_dirs().iter()) {
        builder = builder.clang_arg(format!("-I{}", inc.display()));
    }
    let bindings = builder
        .generate()
        .unwrap_or_else(|e| fail(&format!("bindgen failed on PETSc headers: {e}")));
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("bindings.rs");
    bindings
        .write_to_file(&out)
        .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display())));

    // Expose the configuration to dependents (DEP_PETSC_REAL_VERSION).
    println!("cargo:version={}", petsc.version);
}

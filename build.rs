//! Build-time checks for the fdem crate: PETSc must be 3.18 or newer (the
//! petsc-sys crate also checks scalar and index types) and Open MPI's
//! wrapper must be on the PATH for mpi-sys.

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    match pkg_config::Config::new()
        .cargo_metadata(false)
        .atleast_version("3.18")
        .probe("PETSc")
    {
        Ok(lib) => println!("cargo:rustc-env=FDEM_PETSC_VERSION={}", lib.version),
        Err(e) => {
            println!(
                "cargo:warning=PETSc >= 3.18 not found by pkg-config ({e}); run scripts/setup.sh"
            );
            panic!("PETSc >= 3.18 is required (Debian: petsc-dev); run scripts/setup.sh");
        }
    }
}

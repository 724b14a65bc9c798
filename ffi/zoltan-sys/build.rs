//! Generates raw bindings to Zoltan with bindgen.
//!
//! Debian's `libtrilinos-zoltan-dev` puts `zoltan.h` under
//! `/usr/include/trilinos` and the library in the default search path
//! (`-ltrilinos_zoltan`). Zoltan's view of MPI is block-listed: the MPI
//! types come from `mpi-sys`, so an rsmpi communicator passes straight to
//! `Zoltan_Create`.

use std::env;
use std::path::PathBuf;
use std::process::Command;

fn fail(msg: &str) -> ! {
    eprintln!("error: zoltan-sys: {msg}");
    panic!("zoltan-sys: {msg}");
}

fn mpi_include_dirs() -> Vec<PathBuf> {
    match Command::new("mpicc").arg("--showme:incdirs").output() {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout)
            .split_whitespace()
            .map(PathBuf::from)
            .collect(),
        _ => Vec::new(),
    }
}

fn main() {
    println!("cargo:rerun-if-changed=wrapper.h");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=ZOLTAN_INCLUDE_DIR");
    let include = env::var("ZOLTAN_INCLUDE_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| PathBuf::from("/usr/include/trilinos"));
    if !include.join("zoltan.h").exists() {
        fail(&format!(
            "zoltan.h not found in {} (set ZOLTAN_INCLUDE_DIR). Install Debian's \
             libtrilinos-zoltan-dev (scripts/setup.sh does).",
            include.display()
        ));
    }
    println!("cargo:rustc-link-lib=trilinos_zoltan");
    let mut builder = bindgen::Builder::default()
        .header("wrapper.h")
        .parse_callbacks(Box::new(bindgen::CargoCallbacks::new()))
        .allowlist_function("Zoltan_.*")
        .allowlist_type("(Zoltan_|ZOLTAN_).*")
        .allowlist_var("ZOLTAN_.*")
        .blocklist_item("MPI_.*")
        .blocklist_item("ompi_.*")
        .blocklist_item("FP_.*")
        .default_enum_style(bindgen::EnumVariation::Rust {
            non_exhaustive: false,
        })
        .layout_tests(false)
        .generate_comments(false)
        .clang_arg(format!("-I{}", include.display()));
    for inc in mpi_include_dirs() {
        builder = builder.clang_arg(format!("-I{}", inc.display()));
    }
    let bindings = builder
        .generate()
        .unwrap_or_else(|e| fail(&format!("bindgen failed on zoltan.h: {e}")));
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("bindings.rs");
    bindings
        .write_to_file(&out)
        .unwrap_or_else(|e| fail(&format!("cannot write {}: {e}", out.display())));
}

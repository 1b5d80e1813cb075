//! Linker arguments for cortex-m-rt (link.x) and defmt (defmt.x), as the embassy examples pass them.
fn main() {
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}

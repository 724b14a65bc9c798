# Sourced by the other scripts: environment for Open MPI as root and cargo.
export OMPI_ALLOW_RUN_AS_ROOT=1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_rmaps_base_oversubscribe=1
# Quiet Open MPI's warnings about missing high-speed interconnects in containers.
export OMPI_MCA_btl_base_warn_component_unused=0
export PATH="$HOME/.cargo/bin:$PATH"

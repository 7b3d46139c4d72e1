# Sourced by the README commands: makes sure a Vulkan driver is installed (lavapipe from Debian's
# mesa-vulkan-drivers when there is none), so the GPU code runs on machines without a GPU, and
# that a C++ compiler is there for nv-flip.
if ! compgen -G "/usr/share/vulkan/icd.d/*.json" >/dev/null && ! compgen -G "/etc/vulkan/icd.d/*.json" >/dev/null \
    && [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ]; then
    echo "no Vulkan driver found: installing lavapipe (mesa-vulkan-drivers)" >&2
    if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi
# lavapipe warns about this on every start; give it a private runtime dir.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
# The reyes crate links NVIDIA's FLIP (nv-flip, C++): a C++ compiler must be there to build it.
if ! command -v c++ >/dev/null; then
    echo "no C++ compiler found: installing g++ (for nv-flip)" >&2
    if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq g++ >/dev/null
fi

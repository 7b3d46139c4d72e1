# Sourced on a GPU machine before measuring (docs/results.md, "How to measure"):
#
#   source scripts/device-setup.sh [DEBS_DIR]
#
# 1. The Vulkan loader. A bare NVIDIA machine (a container with the driver mounted) may have the
#    driver but not the loader (libvulkan.so.1). Then the .deb files in DEBS_DIR are unpacked
#    into / (made where the network is: `apt-get download libvulkan1 libegl1 libglvnd0
#    libopengl0 libgl1 libglx0 libgles2`; NVIDIA's Vulkan driver lives in its GLX library,
#    which needs the GL dispatch libraries), else apt-get installs them.
# 2. NVIDIA's Vulkan driver manifest: where the container runtime mounts it outside the loader's
#    search path (under /usr/local/nvidia), VK_DRIVER_FILES names it.
# 3. XDG_RUNTIME_DIR: the loader and Mesa warn on every start without one.
# 4. The record: GPU, driver and maximum SM clock (nvidia-smi), printed.
#
# Clocks need no step here: every timed command (`schedbench`, `reyes render --runs`,
# `reyes bench`, `reyes measure`) first keeps the GPU fully busy for 0.5 s so that the power
# governor has raised the clocks before the timed runs (`scheduler::clocks::raise_clocks`;
# docs/results.md, "GPU clocks: a timing trap"). The device's clock settings are left as they
# are. Sourced, not run: it sets variables in the calling shell and never exits it.

device_setup() {
    local debs="${1:-}"
    if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1 '; then
        if [ -n "$debs" ] && compgen -G "$debs/*.deb" >/dev/null; then
            echo "device-setup: unpacking the Vulkan loader from $debs" >&2
            local f
            for f in "$debs"/*.deb; do dpkg -x "$f" / || return 1; done
            ldconfig
        else
            echo "device-setup: no Vulkan loader: installing libvulkan1 (apt-get)" >&2
            local sudo=; [ "$(id -u)" = 0 ] || sudo=sudo
            $sudo apt-get update -qq \
                && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq libvulkan1 libegl1 \
                    libglvnd0 libopengl0 libgl1 libglx0 libgles2 >/dev/null \
                || return 1
        fi
    fi
    if [ -z "${VK_DRIVER_FILES:-}${VK_ICD_FILENAMES:-}" ] \
        && ! compgen -G "/usr/share/vulkan/icd.d/nvidia_icd*.json" >/dev/null \
        && ! compgen -G "/etc/vulkan/icd.d/nvidia_icd*.json" >/dev/null; then
        local icd
        for icd in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd*.json; do
            if [ -f "$icd" ]; then
                export VK_DRIVER_FILES="$icd"
                echo "device-setup: VK_DRIVER_FILES=$icd" >&2
                break
            fi
        done
    fi
    export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
    if command -v nvidia-smi >/dev/null; then
        nvidia-smi --query-gpu=name,driver_version,clocks.max.sm --format=csv,noheader
    fi
}
device_setup "$@"

# Sourced first on the H200: Vulkan loader, NVIDIA ICD, data dir.
for f in .gl/*.deb; do dpkg -x $f / >/dev/null 2>&1; done; ldconfig
export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
export XDG_RUNTIME_DIR=$(mktemp -d)
export REYES_SHARED_DATA=$PWD/.devbin/data
B=$PWD/.devbin

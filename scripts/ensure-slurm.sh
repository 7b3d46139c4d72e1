# Sourced by ./run-tests: the Slurm test (tests/farm_slurm.rs) starts a real one-node cluster
# (farm/slurm/local-cluster.sh: munged, slurmctld, slurmd on this machine); Debian's slurmd,
# slurmctld, slurm-client and munge are installed when missing. The test fails loudly without
# them, never skips. Debian's packages try to start their services on install; a machine
# without an init system refuses (harmless), and the test starts its own daemons anyway.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null \
    || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
    echo "Slurm or munge missing: installing slurmd, slurmctld, slurm-client and munge (for tests/farm_slurm.rs)" >&2
    if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
        slurmd slurmctld slurm-client munge >/dev/null
fi

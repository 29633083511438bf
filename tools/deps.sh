#!/usr/bin/env bash
# Installs the Debian packages haze needs, and only those that are missing.
# Idempotent: when everything is present it does nothing and needs no root.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libembree-dev      # surfaces (Embree 3 C API)
  libopenexr-dev     # images (OpenEXRCore C API)
  libisal-dev        # the EXR writer's ZIP chunks (ISA-L's igzip: faster than zlib, same streams)
  libpng-dev         # --preview PNG
  zlib1g-dev         # ZIP-compressed .nvdb files (NanoVDB codec)
  libxxhash-dev      # XXH3: the fingerprint of large input files (render id) at memory speed
  libcmocka-dev      # test framework
  libopenvdb-dev libnanovdb-dev  # volumes (OpenVDB 10 + NanoVDB)
  libboost-iostreams-dev         # needed by OpenVDB's headers, not pulled in by libopenvdb-dev
  libopenvdb-tools libnanovdb-tools  # vdb_print, nanovdb_print/convert for checking data
  openimageio-tools  # idiff: haze diff is checked against it
  clang libclang-rt-14-dev  # make fuzz: clang and its libFuzzer runtime (libclang_rt.fuzzer)
  valgrind           # the valgrind_render memcheck test
  libopenmpi-dev openmpi-bin  # MPI: one image across ranks (mpirun), on when found
  gnuplot-nox        # make bench: bench/results/trade.png
  time               # make bench: GNU time's peak memory of haze and its .vdb reader
  python3            # the include_cycles test (tools/include-cycles.py)
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[[ ${#missing[@]} -eq 0 ]] && exit 0

echo "haze: installing missing Debian packages: ${missing[*]}"
sudo_cmd=()
if [[ $(id -u) -ne 0 ]]; then
  command -v sudo >/dev/null || { echo "haze: need root or sudo to install ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
# A stale package list makes install fail; refresh once and retry.
if ! "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"; then
  "${sudo_cmd[@]}" apt-get update
  "${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
fi

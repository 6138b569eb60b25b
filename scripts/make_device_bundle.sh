#!/usr/bin/env bash
# Fill a bundle for scripts/device_bench.sh: everything a GPU machine without internet needs to run
# geocull's benchmarks (docs/DESIGN.md, "Running on a GPU machine"). Run here, where PyPI and
# Debian's packages are reachable:
#
#   scripts/make_device_bundle.sh [--out DIR] [--wheel PATH] [--data DIR] [--python-versions 3.11,3.12]
#                                 [--minimal] [--pyvista] [--tar]
#
# DIR (default out/device_bundle) gets:
#   geocull-*-abi3-*.whl   the extension's abi3 wheel (--wheel, else the newest in dist/: build it with
#                          `.venv/bin/maturin build --release -o dist`, or `make device-bundle`)
#   wheelhouse/            the pure-Python and binary wheels the benches import, for each --python-versions
#                          (default: this venv's), at the versions of this venv (pip download --only-binary):
#                          pip and numpy (every bench); xtgeo and its dependencies (the field bench reads
#                          the Reek files with it; --minimal leaves them out: ~18 MB instead of ~200 MB per
#                          Python version, and device_bench.sh then skips the field scene); pyvista and vtk
#                          with --pyvista (the PyVista columns; off by default: ~150 MB more, and VTK needs
#                          EGL on the GPU machine)
#   debs/                  Debian's libvulkan1 (the Vulkan loader), libegl1 and libglvnd0 (the EGL loader):
#                          device_bench.sh unpacks them into its prefix where the machine has no loader
#                          (an NVIDIA driver brings the ICD, not always the loader)
#   data/reek/             the Reek files the field bench reads (geocull.bench.field.find_files:
#                          surfaces/*.gri, the EGRID, the porosity file, wells/*.w: ~14 MB of the 20 MB)
#   device_bench.sh        a copy of scripts/device_bench.sh (it finds the bundle beside itself)
# --tar also writes DIR.tar.gz. Then, on the GPU machine: bash DIR/device_bench.sh.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/.." && pwd)"
py="$root/.venv/bin/python"
out="$root/out/device_bundle"
wheel=""
data="$root/../shared/data/reek"
pyversions=""
minimal=0
with_pyvista=0
tarball=0

die() { echo "make_device_bundle: $*" >&2; exit 1; }
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --wheel) wheel="$2"; shift 2 ;;
    --data) data="$2"; shift 2 ;;
    --python-versions) pyversions="$2"; shift 2 ;;
    --minimal) minimal=1; shift ;;
    --pyvista) with_pyvista=1; shift ;;
    --tar) tarball=1; shift ;;
    -h|--help) sed -n '2,/^set -/{/^set -/d;p}' "$0"; exit 0 ;;
    *) die "unknown option $1 (see --help)" ;;
  esac
done
[ -x "$py" ] || die "no $py: run make setup first"
[ -n "$pyversions" ] || pyversions="$("$py" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')"

if [ -z "$wheel" ]; then
  wheel="$(ls -t "$root"/dist/geocull-*-abi3-*.whl 2>/dev/null | head -1 || true)"
  [ -n "$wheel" ] || die "no abi3 wheel in dist/: build it with .venv/bin/maturin build --release -o dist"
fi
[ -f "$wheel" ] || die "no wheel $wheel"
case "$(basename "$wheel")" in *abi3*) ;; *) die "$wheel is not an abi3 wheel" ;; esac

rm -rf "$out"
mkdir -p "$out/wheelhouse" "$out/debs" "$out/data/reek"
cp "$wheel" "$out/"
cp "$here/device_bench.sh" "$out/"
echo "make_device_bundle: wheel $(basename "$wheel")"

# The wheels, at this venv's versions (the ones the benches were tested with) where it has them.
pkgs=(pip numpy)
[ "$minimal" = 1 ] || pkgs+=(xtgeo)
[ "$with_pyvista" = 0 ] || pkgs+=(pyvista vtk)
constraints="$(mktemp)"
trap 'rm -f "$constraints"' EXIT
"$py" -m pip freeze --exclude-editable 2>/dev/null | grep -v '^-e \|@ file:\|^geocull' > "$constraints" || true
IFS=',' read -r -a versions <<< "$pyversions"
for v in "${versions[@]}"; do
  echo "make_device_bundle: wheels for CPython $v: ${pkgs[*]} and their dependencies"
  "$py" -m pip download -q --disable-pip-version-check --dest "$out/wheelhouse" --only-binary=:all: \
    --python-version "$v" --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_17_x86_64 --platform manylinux2014_x86_64 \
    -c "$constraints" "${pkgs[@]}"
done

# The loaders, as Debian packages (unpacked by device_bench.sh only where the machine lacks them).
if command -v apt-get >/dev/null; then
  (cd "$out/debs" && { apt-get download libvulkan1 libegl1 libglvnd0 >/dev/null 2>&1 \
     || { apt-get update -qq >/dev/null 2>&1 && apt-get download libvulkan1 libegl1 libglvnd0 >/dev/null; }; }) \
    || echo "make_device_bundle: warning: could not download the loader packages; the GPU machine must have libvulkan1" >&2
else
  echo "make_device_bundle: warning: no apt-get; the bundle carries no loader packages" >&2
fi

# Only the Reek files the field bench reads.
if [ "$minimal" = 0 ]; then
  [ -d "$data" ] || die "no field data at $data (--data DIR)"
  PYTHONPATH="$root/python" "$py" - "$data" "$out/data/reek" <<'EOF'
import shutil, sys
from pathlib import Path
from geocull.bench.field import find_files

src, dst = Path(sys.argv[1]).resolve(), Path(sys.argv[2])
f = find_files(src)
paths = [*f["surfaces"], *f["grid"], *f["wells"]] + ([f["poro"]] if f["poro"] is not None else [])
if f["poro"] is None:  # PORO of an INIT file beside the EGRID
    paths += [p for p in f["grid"][0].parent.glob(f["grid"][0].stem + ".*") if p.suffix.lower() == ".init"]
for p in paths:
    q = dst / Path(p).resolve().relative_to(src)
    q.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(p, q)
print(f"make_device_bundle: {len(paths)} field files ({sum(Path(p).stat().st_size for p in paths) / 1e6:.1f} MB) of {src}")
EOF
else
  rmdir "$out/data/reek" "$out/data"
fi

echo "make_device_bundle: $out ($(du -sh "$out" | cut -f1)): wheelhouse $(du -sh "$out/wheelhouse" | cut -f1), $(ls "$out/debs" | wc -l) loader packages"
if [ "$tarball" = 1 ]; then
  tar -C "$(dirname "$out")" -czf "$out.tar.gz" "$(basename "$out")"
  echo "make_device_bundle: $out.tar.gz ($(du -sh "$out.tar.gz" | cut -f1))"
fi
echo "make_device_bundle: on the GPU machine: bash $(basename "$out")/device_bench.sh"

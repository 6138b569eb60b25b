#!/usr/bin/env bash
# geocull's benchmarks on a GPU machine without internet (docs/DESIGN.md, "Running on a GPU machine").
#
#   bash device_bench.sh [--bundle DIR] [--out DIR] [--budget SECONDS] [--steps quick,field,grid,iso,full]
#                        [--small] [--allow-cpu] [--pyvista] [--keep] [--python PYTHON]
#
# The bundle (scripts/make_device_bundle.sh; default: the folder this script is in when it holds a
# wheelhouse/, else out/device_bundle of the checkout) holds the abi3 wheel, a wheelhouse, Debian's
# loader packages and the Reek files. The script
#   1. makes a temporary prefix with a venv (python3 -m venv; Python >= 3.11) and installs the wheel and
#      the wheelhouse's numpy (+ xtgeo where carried, + pyvista with --pyvista) with
#      pip install --no-index --find-links WHEELHOUSE: nothing is downloaded;
#   2. where the machine has no Vulkan loader (libvulkan.so.1), unpacks the bundle's libvulkan1 (and the EGL
#      loader) into the prefix; where an NVIDIA driver's library is there but no Vulkan ICD file names it (a
#      container given the driver without its graphics part), writes one;
#   3. checks the adapter geocull renders on (Renderer.adapter_info): a CPU device (lavapipe, llvmpipe,
#      SwiftShader, a software rasteriser) fails the run loudly, exit 3, unless --allow-cpu;
#   4. runs the benchmarks, each bounded in time, with the geocull installed in the prefix (never a checkout's):
#        quick  python -m geocull bench --quick               (Gullfaks-like scene, 320x256, 3 views)
#        field  python -m geocull bench --scene field --views 4 --repeats 3 --data BUNDLE/data/reek (1280x1024)
#        grid   python -m geocull bench --scene grid          (100x100x100 cells)
#        iso    python -m geocull bench --scene iso --iso-volumes pesco --views 4   (512x512, 128^3)
#        full   python -m geocull bench --views 3 --no-horizon (the Gullfaks-like scene, 3.9 M triangles, 1280x1024)
#        scale  python -m geocull bench --scene scale         (3.9 M, 15 M, 61 M triangles; not in the default steps)
#      all with --no-pyvista unless --pyvista. --small: each in its smallest variant (to try the script on a
#      CPU with --allow-cpu). A step gets at most its own limit and what is left of --budget (default 480 s,
#      the whole run within ~8 min); a step with under 20 s left is skipped;
#   5. prints each step's table, then a summary (adapter, each step's status and time), and leaves the
#      tables, logs and JSON in --out (default ./device_bench_out, or $OUT where that is set).
# Exit status: 0 when every step ran, 1 when one failed or timed out, 2 for a set-up error, 3 for a CPU adapter.
set -uo pipefail

t_start=$(date +%s)
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
bundle=""
outdir="${OUT:-$PWD/device_bench_out}"
budget=480
steps="quick,field,grid,iso,full"
small=0
allow_cpu=0
with_pyvista=0
keep=0
python="${PYTHON:-}"

say() { echo "device_bench: $*" >&2; }
die() { echo "device_bench: ERROR: $*" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --bundle) bundle="$2"; shift 2 ;;
    --out) outdir="$2"; shift 2 ;;
    --budget) budget="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    --small) small=1; shift ;;
    --allow-cpu) allow_cpu=1; shift ;;
    --pyvista) with_pyvista=1; shift ;;
    --keep) keep=1; shift ;;
    --python) python="$2"; shift 2 ;;
    -h|--help) sed -n '2,/^set -/{/^set -/d;p}' "$0"; exit 0 ;;
    *) die "unknown option $1 (see --help)" ;;
  esac
done
if [ -z "$bundle" ]; then
  if [ -d "$here/wheelhouse" ]; then bundle="$here"; else bundle="$here/../out/device_bundle"; fi
fi
[ -d "$bundle/wheelhouse" ] || die "no bundle at $bundle (make it with scripts/make_device_bundle.sh; --bundle DIR)"
bundle="$(cd "$bundle" && pwd)"
wh="$bundle/wheelhouse"
wheel="$(ls -t "$bundle"/geocull-*-abi3-*.whl 2>/dev/null | head -1)"
[ -n "$wheel" ] || die "no geocull abi3 wheel in $bundle"
mkdir -p "$outdir" || die "cannot create $outdir"
outdir="$(cd "$outdir" && pwd)"

# --- 1. Python and the prefix ------------------------------------------------------------------------
if [ -z "$python" ]; then
  for c in python3 python3.13 python3.12 python3.11 python3.14; do
    if command -v "$c" >/dev/null && "$c" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
      python="$(command -v "$c")"; break
    fi
  done
fi
[ -n "$python" ] || die "no Python >= 3.11 on PATH (geocull's wheel is abi3 for CPython >= 3.11; --python PATH)"
pyver="$("$python" -c 'import sys; print(f"{sys.version_info[0]}{sys.version_info[1]}")')"
ls "$wh"/numpy-*-cp"$pyver"-*.whl >/dev/null 2>&1 \
  || die "the wheelhouse has no numpy for CPython ${pyver:0:1}.${pyver:1} ($python): make the bundle with --python-versions ${pyver:0:1}.${pyver:1}"

prefix="$(mktemp -d "${TMPDIR:-/tmp}/geocull-device.XXXXXX")"
cleanup() { if [ "$keep" = 1 ]; then say "kept the prefix $prefix"; else rm -rf "$prefix"; fi; }
trap cleanup EXIT
say "prefix $prefix, $("$python" --version 2>&1) ($python), bundle $bundle"
if ! "$python" -m venv "$prefix/venv" >/dev/null 2>&1; then
  # No ensurepip (Debian without python3-venv): a bare venv, then pip from the wheelhouse's pip wheel.
  rm -rf "$prefix/venv"
  "$python" -m venv --without-pip "$prefix/venv" || die "python -m venv failed"
  pipwhl="$(ls "$wh"/pip-*.whl 2>/dev/null | head -1)"
  [ -n "$pipwhl" ] || die "no ensurepip and no pip wheel in the wheelhouse"
  "$prefix/venv/bin/python" "$pipwhl/pip" install -q --no-index --find-links "$wh" pip || die "installing pip failed"
fi
vpy="$prefix/venv/bin/python"
reqs=(numpy)
have_xtgeo=0
if ls "$wh"/xtgeo-*-cp"$pyver"-*.whl >/dev/null 2>&1; then reqs+=(xtgeo); have_xtgeo=1; fi
if [ "$with_pyvista" = 1 ]; then reqs+=(pyvista); fi
say "installing $(basename "$wheel") ${reqs[*]} from the wheelhouse (no index)"
PIP_DISABLE_PIP_VERSION_CHECK=1 "$vpy" -m pip install -q --no-index --find-links "$wh" "$wheel" "${reqs[@]}" \
  || die "pip install failed (a wheel for this machine missing? the geocull wheel needs glibc >= its manylinux tag: $(basename "$wheel"))"

# --- 2. The loaders and the NVIDIA ICD ---------------------------------------------------------------
libdirs=""
ldcache="$( (ldconfig -p || /sbin/ldconfig -p) 2>/dev/null)"   # (not piped into grep -q: pipefail and SIGPIPE)
if ! grep -q 'libvulkan\.so\.1' <<< "$ldcache"; then
  debs=("$bundle"/debs/*.deb)
  if [ -e "${debs[0]}" ]; then
    mkdir -p "$prefix/sys"
    for d in "${debs[@]}"; do
      if command -v dpkg-deb >/dev/null; then dpkg-deb -x "$d" "$prefix/sys"
      else (cd "$prefix/sys" && ar p "$d" "$(ar t "$d" | grep '^data\.tar')" | tar -x -f - 2>/dev/null) || true; fi
    done
    libdirs="$(find "$prefix/sys" -name 'libvulkan.so.1' -printf '%h\n' | sort -u | paste -sd:)"
    say "no Vulkan loader on the machine: using the bundle's ($libdirs)"
    export LD_LIBRARY_PATH="$libdirs${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  else
    say "warning: no Vulkan loader on the machine and none in the bundle"
  fi
fi
icd_dirs=(/usr/share/vulkan/icd.d /etc/vulkan/icd.d /usr/local/share/vulkan/icd.d)
icd_files=()
for d in "${icd_dirs[@]}"; do for f in "$d"/*.json; do [ -e "$f" ] && icd_files+=("$f"); done; done
if [ "${#icd_files[@]}" = 0 ] || ! grep -qil nvidia "${icd_files[@]}"; then
  nvlib="$(awk '/libGLX_nvidia\.so\.0/ {print $NF; exit}' <<< "$ldcache")"
  if [ -n "$nvlib" ]; then
    mkdir -p "$prefix/icd"
    printf '{"file_format_version": "1.0.0", "ICD": {"library_path": "%s", "api_version": "1.3.0"}}\n' "$nvlib" \
      > "$prefix/icd/nvidia_icd.json"
    export VK_ADD_DRIVER_FILES="$prefix/icd/nvidia_icd.json${VK_ADD_DRIVER_FILES:+:$VK_ADD_DRIVER_FILES}"
    say "no Vulkan ICD file names the NVIDIA driver: wrote one for $nvlib"
  fi
fi
command -v nvidia-smi >/dev/null && nvidia-smi -L 2>/dev/null | sed 's/^/device_bench: nvidia-smi: /' >&2

# --- 3. The adapter ----------------------------------------------------------------------------------
run_dir="$prefix/run"   # the benches run here: `python -m geocull` must import the prefix's geocull
mkdir -p "$run_dir"
adapter="$(cd "$run_dir" && "$vpy" - 2>"$outdir/adapter.err" <<'EOF'
import sys
import geocull as gc
if not gc.__file__.startswith(sys.prefix):
    sys.exit(f"geocull imported from {gc.__file__}, not from the prefix {sys.prefix}")
print(gc.Renderer(64, 64).adapter_info)
EOF
)" || { cat "$outdir/adapter.err" >&2; die "no adapter: geocull could not open a renderer (ICD files: ${icd_files[*]:-none})"; }
echo "$adapter" > "$outdir/adapter.txt"
say "adapter: $adapter"
lc="$(echo "$adapter" | tr '[:upper:]' '[:lower:]')"
cpu=0
case "$lc" in *llvmpipe*|*lavapipe*|*softpipe*|*swiftshader*|*software*|*"basic render"*|*", cpu,"*|*"(cpu"*) cpu=1 ;; esac
if [ "$cpu" = 1 ]; then
  if [ "$allow_cpu" = 1 ]; then
    say "WARNING: the adapter is a CPU (software) device; going on because of --allow-cpu: these are no GPU numbers"
  else
    cat >&2 <<EOF
device_bench: ============================================================================
device_bench: FAILED: geocull renders on a CPU device, not on the GPU:
device_bench:   $adapter
device_bench: The NVIDIA Vulkan driver was not found by the loader. Check: nvidia-smi; an ICD file naming
device_bench: libGLX_nvidia.so.0 in ${icd_dirs[*]} (containers need the driver's graphics
device_bench: capability: NVIDIA_DRIVER_CAPABILITIES=all); VK_LOADER_DEBUG=error,driver for the loader's view.
device_bench: (--allow-cpu runs anyway, to test this script.)
device_bench: ============================================================================
EOF
    exit 3
  fi
elif [[ "$lc" != *nvidia* ]]; then
  say "note: the adapter is a GPU but not NVIDIA's"
fi

# --- 4. The benchmarks -------------------------------------------------------------------------------
pv=(--no-pyvista)
[ "$with_pyvista" = 1 ] && pv=()
data="$bundle/data/reek"
step_args() {  # the step's bench arguments and its own time limit (seconds), or nothing: not runnable
  local s="$1"
  if [ "$small" = 1 ]; then
    case "$s" in
      quick) echo "60|--quick --views 1 --repeats 1 --no-horizon" ;;
      field) echo "120|--scene field --quick --views 1 --repeats 1 --data $data" ;;
      grid)  echo "90|--scene grid --quick --repeats 1" ;;
      iso)   echo "90|--scene iso --quick --iso-volumes pesco --views 1" ;;
      full)  echo "120|--quick --views 1 --repeats 1 --no-horizon" ;;
      scale) echo "120|--scene scale --tiny" ;;
    esac
  else
    local iv="pesco"; [ "$with_pyvista" = 1 ] && iv="pesco,channels,frog"
    case "$s" in
      quick) echo "60|--quick" ;;
      field) echo "180|--scene field --views 4 --repeats 3 --data $data" ;;
      grid)  echo "90|--scene grid" ;;
      iso)   echo "90|--scene iso --iso-volumes $iv --views 4" ;;
      full)  echo "150|--views 3 --no-horizon" ;;
      scale) echo "300|--scene scale" ;;
    esac
  fi
}
summary=()
failed=0
IFS=',' read -r -a step_list <<< "$steps"
for s in "${step_list[@]}"; do
  spec="$(step_args "$s")"
  [ -n "$spec" ] || { say "unknown step $s (quick, field, grid, iso, full, scale)"; summary+=("$s|unknown|-"); failed=1; continue; }
  limit="${spec%%|*}"; args="${spec#*|}"
  if [ "$s" = field ] && { [ "$have_xtgeo" = 0 ] || [ ! -d "$data" ]; }; then
    say "skipping field: the bundle has no xtgeo or no data/reek (made with --minimal?)"
    summary+=("$s|skipped (no xtgeo/data)|-"); continue
  fi
  left=$(( budget - ($(date +%s) - t_start) ))
  [ "$left" -lt "$limit" ] && limit="$left"
  if [ "$limit" -lt 20 ]; then
    say "skipping $s: ${left}s of the ${budget}s budget left"
    summary+=("$s|skipped (budget)|-"); continue
  fi
  say "=== $s: python -m geocull bench $args ${pv[*]} (at most ${limit}s)"
  t0=$(date +%s)
  # shellcheck disable=SC2086
  (cd "$run_dir" && timeout -k 10 "$limit" "$vpy" -m geocull bench $args "${pv[@]}" --json "$outdir/$s.json" \
     > "$outdir/$s.txt" 2> >(tee "$outdir/$s.log" >&2))
  rc=$?
  dt=$(( $(date +%s) - t0 ))
  case "$rc" in
    0) st="ok" ;;
    124|137) st="TIMED OUT after ${limit}s"; failed=1 ;;
    *) st="FAILED (exit $rc; $outdir/$s.log)"; failed=1 ;;
  esac
  summary+=("$s|$st|${dt}s")
done

# --- 5. The tables and the summary -------------------------------------------------------------------
for s in "${step_list[@]}"; do
  if [ -s "$outdir/$s.txt" ]; then
    echo
    echo "=== $s ==="
    cat "$outdir/$s.txt"
  fi
done
{
  echo
  echo "=== device_bench summary ($(date -u +%Y-%m-%dT%H:%MZ), $(( $(date +%s) - t_start ))s of ${budget}s) ==="
  echo "adapter: $adapter$([ "$cpu" = 1 ] && echo '   <-- CPU device (--allow-cpu): not GPU numbers')"
  echo "geocull: $(basename "$wheel"); $("$vpy" --version 2>&1); host $(uname -n), $(nproc) cores"
  for row in "${summary[@]}"; do
    IFS='|' read -r n st dt <<< "$row"
    printf '  %-6s %-40s %s\n' "$n" "$st" "$dt"
  done
  echo "tables, logs, JSON: $outdir"
} | tee "$outdir/summary.txt"
exit "$failed"

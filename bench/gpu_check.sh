#!/bin/bash
# The GPU check of issue 46 (item 4's figures on a GPU host), in under 5 minutes, on a host
# with nothing but the NVIDIA driver: it runs the programs of a bundle made by
# ../shared/gpu/bundle.sh (docs/ACCURACY.md, "GPU check").
#
#   bench/gpu_check.sh [BUNDLE_DIR]          the bundle's programs through BUNDLE_DIR/run.sh
#                                            (default: this script's folder when it holds
#                                            run.sh, i.e. a copy inside the bundle, else .gpu)
#   NEPHELE_BIN=build bench/gpu_check.sh --local
#                                            a build folder's programs directly (a dry run)
#   QUICK=1 ...                              tiny settings: 640x480, 2 repeats, one preset
#
# Settings (environment): SIZE_HD (1920x1080), SIZE_UHD (3840x2160), REPEATS (9), PRESETS
# (comma-separated; default every genus_* preset and cloudscape), SECONDS_DAEMON (10, the
# daemon's timed window), SAMPLES (24, dataset samples), TOTAL_S (285, the whole run's limit).
#
# The figures and where they come from:
#   1. every sky at SIZE_HD within 4 ms (aim 2) and at SIZE_UHD within 12 ms: genus_bench
#      --still, the median "still ms" of each preset's every view (render + readback into an
#      8-bit target), one run per size so a slow size cannot take the other's figures with it;
#   2. four SIZE_HD channels of the cloudscape at 60 Hz through the daemon: daemon_bench has no
#      options (640x480 views of cumulus.toml; 1, 4 and 16 subscribers of one view, whose
#      frame is rendered once for all; lockstep host frames with 1 and 3 views), and in a
#      bundle it stops at its PNG request (no image encoder there). So this script starts
#      `nephele serve` itself on cloudscape.toml with four raw SIZE_HD views in a ring
#      (headings 200, 290, 20, 110), realtime at 60 Hz, subscribes each at 60 Hz on its own
#      connection (bash /dev/tcp), reads every byte for SECONDS_DAEMON seconds after a warm-up,
#      and reports the frames each channel received per second, the frames rendered per
#      second and the render time per view (stats: render_ms), with frames_dropped.
#      daemon_bench also runs, last, for its 4-subscriber line (one 640x480 view, 60 Hz);
#   3. readback and conversion of a SIZE_HD frame within 1 ms: "readback" of the budget lines
#      (bench_common.h frameBudgetLine; glReadPixels and the CPU's channels) genus_bench prints
#      under each SIZE_HD case, the largest of them;
#   4. the example dataset (config/datasets/EXAMPLE.toml) at 150 samples/s or more:
#      dataset_bench on it. `nephele dataset` cannot serve: it writes image files, which a
#      bundle cannot. dataset_bench times each stage in memory and bounds the three-thread
#      pipeline of `nephele dataset` by its slowest stage; in a bundle its PNG stages encode
#      nothing (0 ms), so there the rate leaves out PNG encoding;
#   5. memory: genus_bench's resident and peak lines, the daemon's VmRSS and VmHWM at the end
#      of its window, and each program's peak resident memory sampled every 0.5 s.
#
# Everything goes to the terminal and to $OUT/gpu_check.log ($OUT set) or ./gpu_check.log.
set -euo pipefail

usage() { awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$0"; }

here=$(cd "$(dirname "$0")" && pwd)
mode=bundle
bundle=
case ${1:-} in
  -h | --help) usage; exit 0 ;;
  --local) mode=local ;;
  "") ;;
  *) bundle=$1 ;;
esac
if [[ $mode == bundle ]]; then
  if [[ -z $bundle ]]; then
    if [[ -x $here/run.sh && -d $here/bin ]]; then bundle=$here; else bundle=.gpu; fi
  fi
  [[ -x $bundle/run.sh && -d $bundle/bin ]] || {
    echo "gpu_check: $bundle is not a bundle (no run.sh and bin/); make one with ../shared/gpu/bundle.sh BUILD_DIR .gpu, or use --local" >&2
    exit 2
  }
  G=$(cd "$bundle" && pwd)
  RUN=("$G/run.sh")
  NEPHELE=$G/bin/nephele
  BENCH=$G/bin
  SRC=$G/src
else
  bin=${NEPHELE_BIN:-build}
  [[ -x $bin/nephele ]] || { echo "gpu_check: no $bin/nephele (set NEPHELE_BIN)" >&2; exit 2; }
  bin=$(cd "$bin" && pwd)
  RUN=()
  NEPHELE=$bin/nephele
  BENCH=$bin/bench
  SRC=$(cd "$here/.." && pwd)
fi
SCENES=$SRC/config/scenes
EXAMPLE=$SRC/config/datasets/EXAMPLE.toml

if [[ ${QUICK:-0} == 1 ]]; then
  : "${SIZE_HD:=640x480}" "${SIZE_UHD:=640x480}" "${REPEATS:=2}" "${PRESETS:=genus_cumulus}"
  : "${SECONDS_DAEMON:=4}" "${SAMPLES:=2}"
  warm_daemon=2
else
  : "${SIZE_HD:=1920x1080}" "${SIZE_UHD:=3840x2160}" "${REPEATS:=9}" "${PRESETS:=}"
  : "${SECONDS_DAEMON:=10}" "${SAMPLES:=24}"
  warm_daemon=3
fi
: "${TOTAL_S:=285}"

LOG=${OUT:+$OUT/}gpu_check.log
exec > >(tee "$LOG") 2>&1
tee_pid=$!

work=$(mktemp -d "${TMPDIR:-/tmp}/gpu_check.XXXXXX")
serve_pid=
cleanup() {
  [[ -n $serve_pid ]] && kill "$serve_pid" 2>/dev/null && wait "$serve_pid" 2>/dev/null
  rm -rf "$work"
}
trap cleanup EXIT

echo "# Nephele GPU check, $(date -u +%Y-%m-%dT%H:%M:%SZ), $mode mode${QUICK:+, QUICK=$QUICK}"
echo "programs: $NEPHELE and $BENCH/*"
echo "host: $(uname -n), $(nproc) cores, $(awk '/MemTotal/ {printf "%.0f GiB", $2 / 1048576}' /proc/meminfo)"
smi=$(command -v nvidia-smi || true)
[[ -z $smi && -x /usr/local/nvidia/bin/nvidia-smi ]] && smi=/usr/local/nvidia/bin/nvidia-smi
card="(no nvidia-smi)"
if [[ -n $smi ]]; then
  card=$("$smi" --query-gpu=name,driver_version --format=csv,noheader 2>&1 | head -1) || true
elif [[ -r /proc/driver/nvidia/version ]]; then
  card="driver: $(head -1 /proc/driver/nvidia/version)"
fi
echo "card, driver: $card"
echo "settings: sizes $SIZE_HD and $SIZE_UHD, repeats $REPEATS, presets ${PRESETS:-genus_* and cloudscape}, daemon window ${SECONDS_DAEMON} s, dataset samples $SAMPLES, at most $TOTAL_S s"

# The limit for a step: its own, or what is left of TOTAL_S less a margin for the summary.
limit() {
  local left=$((TOTAL_S - SECONDS - 5))
  ((left < $1)) && echo "$left" || echo "$1"
}

# Peak resident memory (VmHWM, MiB) of PID's descendants, sampled every 0.5 s while PID runs:
# "name peak" lines, the largest per program name.
declare -A peak_mib=()
descendants() {
  local p
  # shellcheck disable=SC2013  # one pid a word
  for p in $(cat /proc/"$1"/task/*/children 2>/dev/null); do
    echo "$p"
    descendants "$p"
  done
}
watch_memory() {
  local pid=$1 p name kb
  while kill -0 "$pid" 2>/dev/null; do
    for p in $(descendants "$pid"); do
      name=$(cat /proc/"$p"/comm 2>/dev/null) || continue
      kb=$(awk '/^VmHWM:/ {print $2}' /proc/"$p"/status 2>/dev/null) || continue
      [[ -n $kb ]] || continue
      ((kb / 1024 > ${peak_mib[$name]:-0})) && peak_mib[$name]=$((kb / 1024))
    done
    sleep 0.5
  done
}

# step NAME LIMIT_S COMMAND...: runs COMMAND (through run.sh in a bundle) under timeout,
# output to the terminal and to $work/NAME.out; the exit status in $work/NAME.rc.
step() {
  local name=$1 lim
  lim=$(limit "$2")
  shift 2
  echo
  echo "## $name (limit ${lim} s): $(basename "$1") ${*:2}"
  if ((lim < 10)); then
    echo "skipped: the run's $TOTAL_S s are spent"
    echo skipped > "$work/$name.rc"
    : > "$work/$name.out"
    return
  fi
  local start=$SECONDS rc=0
  (timeout -k 5 "$lim" "${RUN[@]}" "$@" 2>&1 | tee "$work/$name.out") &
  local pid=$!
  peak_mib=()
  watch_memory "$pid"
  wait "$pid" || rc=$?
  echo "$rc" > "$work/$name.rc"
  local mem="" n
  for n in "${!peak_mib[@]}"; do
    [[ $n == tee || $n == timeout || $n == bash ]] || mem+=" $n ${peak_mib[$n]} MiB"
  done
  echo "-- $name: exit $rc$( ((rc == 124 || rc == 137)) && echo ' (timed out)'), $((SECONDS - start)) s; peak resident (sampled):${mem:- none seen}"
  echo "${mem# }" > "$work/$name.mem"
}

presets=()
[[ -n $PRESETS ]] && presets=(--presets "$PRESETS")

# 1 and 3: the skies and the readback.
step genus_hd 90 "$BENCH/genus_bench" --still --sizes "$SIZE_HD" --repeats "$REPEATS" --dir "$SCENES" "${presets[@]}"
step genus_uhd 90 "$BENCH/genus_bench" --still --sizes "$SIZE_UHD" --repeats "$REPEATS" --dir "$SCENES" "${presets[@]}"

# 2: four channels of the cloudscape through the daemon.
daemon_check() {
  local w=${SIZE_HD%x*} h=${SIZE_HD#*x} cfg=$work/serve.toml views=(front right back left)
  local headings=(200 290 20 110) i
  {
    echo "scene = \"$SCENES/cloudscape.toml\""
    printf '[world]\nmode = "realtime"\ntick_rate = 60.0\n'
    for i in 0 1 2 3; do
      printf '[[view]]\nname = "%s"\nheading = %s.0\nwidth = %s\nheight = %s\nformat = "raw"\n' \
        "${views[i]}" "${headings[i]}" "$w" "$h"
    done
    # Room for 30 frames a client: a reader's hiccup drops none (drops are counted anyway).
    printf '[socket]\nport = 0\nmax_pending_mb = 256\n[modbus]\nenabled = false\n'
    printf '[output]\ndirectory = "%s/frames"\n' "$work"
  } > "$cfg"
  "${RUN[@]}" "$NEPHELE" serve -c "$cfg" > "$work/serve.ready" 2> "$work/serve.log" &
  serve_pid=$!
  echo "$serve_pid" > "$work/serve.pid"
  local port=""
  for _ in $(seq 150); do
    port=$(sed -n 's/^nephele ready socket=\([0-9]*\).*/\1/p' "$work/serve.ready")
    [[ -n $port ]] && break
    kill -0 "$serve_pid" 2>/dev/null || break
    sleep 0.2
  done
  grep -m1 'event=world_ready' "$work/serve.log" || true
  if [[ -z $port ]]; then
    echo "the daemon did not start:"; tail -5 "$work/serve.log"
    return 1
  fi
  stats() {
    local fd line
    exec {fd}<>"/dev/tcp/127.0.0.1/$port"
    printf '{"id":"check","cmd":"stats"}\n' >&"$fd"
    IFS= read -r -t 10 line <&"$fd" || true
    exec {fd}>&-
    echo "$line"
  }
  local drainers=()
  for i in 0 1 2 3; do
    (
      exec 3<>"/dev/tcp/127.0.0.1/$port"
      printf '{"id":1,"cmd":"subscribe","view":"%s","rate":60,"format":"raw"}\n' "${views[i]}" >&3
      timeout "$warm_daemon" cat <&3 > /dev/null || true
      timeout "$SECONDS_DAEMON" cat <&3 | wc -c > "$work/bytes.${views[i]}" || true
    ) &
    drainers+=($!)
  done
  sleep "$warm_daemon"
  local s0 s1 t0 t1
  t0=$(date +%s.%N); s0=$(stats)
  sleep "$SECONDS_DAEMON"
  t1=$(date +%s.%N); s1=$(stats)
  wait "${drainers[@]}" || true
  local rss hwm
  rss=$(awk '/^VmRSS:/ {printf "%.0f", $2 / 1024}' /proc/"$serve_pid"/status 2>/dev/null || echo "?")
  hwm=$(awk '/^VmHWM:/ {printf "%.0f", $2 / 1024}' /proc/"$serve_pid"/status 2>/dev/null || echo "?")
  kill "$serve_pid" 2>/dev/null || true
  wait "$serve_pid" 2>/dev/null || true
  serve_pid=
  num() { grep -o "\"$1\":[0-9.e+-]*" <<< "$2" | head -1 | cut -d: -f2; }
  local f0 f1 d0 d1 r
  f0=$(num frames "$s0"); f1=$(num frames "$s1")
  d0=$(num frames_dropped "$s0"); d1=$(num frames_dropped "$s1")
  r=$(grep -o '"render_ms":{[^}]*}' <<< "$s1" || true)
  echo "stats at the end: $r; ticks_per_second $(num ticks_per_second "$s1")"
  echo "last frame's budget: $(grep -o '"ms":{[^}]*}' <<< "$s1" || true)"
  awk -v f0="${f0:-0}" -v f1="${f1:-0}" -v d0="${d0:-0}" -v d1="${d1:-0}" -v t0="$t0" -v t1="$t1" \
    -v p50="$(num p50 "$r")" -v p99="$(num p99 "$r")" 'BEGIN {
      s = t1 - t0
      printf "rendered: %.1f frames/s per channel over %.1f s (4 channels); dropped %d; render per view p50 %.2f ms, p99 %.2f ms\n", (f1 - f0) / s / 4, s, d1 - d0, p50, p99 }'
  for i in 0 1 2 3; do
    awk -v v="${views[i]}" -v b="$(cat "$work/bytes.${views[i]}" 2>/dev/null || echo 0)" \
      -v n=$((w * h * 4)) -v s="$SECONDS_DAEMON" \
      'BEGIN { printf "received %s: %.1f frames/s (%d bytes in %d s)\n", v, b / n / s, b, s }'
  done
  echo "daemon memory at the end: resident $rss MiB, peak $hwm MiB"
}
echo
echo "## daemon: four ${SIZE_HD} raw channels of cloudscape.toml, realtime 60 Hz, each subscribed at 60 Hz"
daemon_limit=$(limit $((SECONDS_DAEMON + warm_daemon + 30)))
if ((daemon_limit < 10 + SECONDS_DAEMON)); then
  echo "skipped: the run's $TOTAL_S s are spent"
  : > "$work/daemon.out"
else
  start=$SECONDS
  # The daemon check runs in this shell (the daemon is a background job it ends itself); a
  # watchdog ends the daemon should the check hang past its limit.
  (sleep "$daemon_limit" && kill "$(cat "$work/serve.pid")") > /dev/null 2>&1 &
  watchdog=$!
  daemon_check > >(tee "$work/daemon.out") 2>&1 || echo "the daemon check failed"
  sleep 0.2
  kill "$watchdog" 2>/dev/null || true
  echo "-- daemon: $((SECONDS - start)) s"
fi

# 4: the example dataset.
step dataset 35 "$BENCH/dataset_bench" --samples "$SAMPLES" "$EXAMPLE"

# 2, daemon_bench's own figures (no options; see above).
step daemon_bench 30 "$BENCH/daemon_bench"

# The summary.
echo
echo "## Summary"
gl=$(grep -h -m1 '^GL: ' "$work/genus_hd.out" "$work/genus_uhd.out" 2>/dev/null | head -1 | sed 's/^GL: //; s/; render.*//' || true)
echo
echo "GL: ${gl:-unknown}; card, driver: $card; $(uname -n); $(date -u +%Y-%m-%d)"
[[ ${gl:-} == *llvmpipe* ]] && echo "(software GL: these are not GPU figures)"
[[ ${QUICK:-0} == 1 ]] && echo "(QUICK: small sizes and repeats, one preset: not the targets' sizes)"
echo
echo "| figure | target | measured | met |"
echo "| --- | --- | --- | --- |"

# Still frames of one size: "cases worst_ms worst_case n_within_a n_within_b max_readback
# max_readback_case peak_MiB".
skies() {
  awk -v a="$2" -v b="$3" '
    /^  budget, still:/ && cur != "" {
      for (i = 1; i < NF; ++i) if ($i == "readback" && $(i + 1) + 0 > rb) { rb = $(i + 1) + 0; rbc = cur }
      next
    }
    /^  budget, clear:/ { next }
    /^  memory after/ { for (i = 1; i < NF; ++i) if ($i == "peak" && $(i + 1) + 0 > mem) mem = $(i + 1) + 0; next }
    {
      for (i = 1; i <= NF - 3; ++i) if ($i ~ /^[0-9]+x[0-9]+$/) break
      if (i > NF - 3 || $1 == "preset") { cur = ""; next }
      still = $(i + 3) + 0; cur = $1 "/" $2; ++n
      if (still > worst) { worst = still; wc = cur }
      if (still <= a) ++na
      if (still <= b) ++nb
    }
    END { printf "%d %.2f %s %d %d %.2f %s %d\n", n, worst, (wc == "" ? "-" : wc), na, nb, rb, (rbc == "" ? "-" : rbc), mem }
  ' "$1"
}
verdict() { awk -v x="$1" -v op="$2" -v t="$3" 'BEGIN { ok = (op == "<=") ? x <= t : x >= t; print ok ? "yes" : "no" }'; }
status_of() {
  local rc
  rc=$(cat "$work/$1.rc" 2>/dev/null || echo "not run")
  case $rc in
    0) echo "" ;;
    124 | 137) echo " (timed out: partial)" ;;
    skipped) echo " (skipped: no time left)" ;;
    *) echo " (exit $rc)" ;;
  esac
}

read -r n worst wc na nb rb rbc mem < <(skies "$work/genus_hd.out" 4 2) || n=0
if ((n > 0)); then
  echo "| every sky, still frame at $SIZE_HD ($n preset views) | <= 4 ms (aim 2) | worst $worst ms ($wc); $na of $n within 4, $nb within 2$(status_of genus_hd) | $(verdict "$worst" '<=' 4) |"
  echo "| readback and conversion at $SIZE_HD (largest of the budget lines) | <= 1 ms | $rb ms ($rbc) | $(verdict "$rb" '<=' 1) |"
else
  echo "| every sky, still frame at $SIZE_HD | <= 4 ms (aim 2) | not measured$(status_of genus_hd) | - |"
  echo "| readback and conversion at $SIZE_HD | <= 1 ms | not measured | - |"
fi
mem_hd=$mem
((${mem_hd:-0} > 0)) || mem_hd="?"
read -r n worst wc na nb rb rbc mem < <(skies "$work/genus_uhd.out" 12 6) || n=0
if ((n > 0)); then
  echo "| every sky, still frame at $SIZE_UHD ($n preset views) | <= 12 ms | worst $worst ms ($wc); $na of $n within 12$(status_of genus_uhd) | $(verdict "$worst" '<=' 12) |"
else
  echo "| every sky, still frame at $SIZE_UHD | <= 12 ms | not measured$(status_of genus_uhd) | - |"
fi
mem_uhd=$mem
((${mem_uhd:-0} > 0)) || mem_uhd="?"

recv_min=$(awk '/^received / { v = $3 + 0; if (m == "" || v < m) m = v } END { print m }' "$work/daemon.out")
if [[ -n $recv_min ]]; then
  rendered=$(sed -n 's/^rendered: \([0-9.]*\) frames.*p50 \([0-9.]*\) ms, p99 \([0-9.]*\) ms.*/\1 frames\/s rendered per channel, one view rendered in \2 ms (p50), \3 ms (p99)/p' "$work/daemon.out")
  dropped=$(sed -n 's/.*dropped \([0-9]*\);.*/\1/p' "$work/daemon.out")
  echo "| 4 channels of cloudscape at $SIZE_HD through the daemon (slowest channel's frames received) | 60 Hz (met at >= 59) | $recv_min Hz; $rendered; ${dropped:-?} dropped | $(verdict "$recv_min" '>=' 59) |"
else
  echo "| 4 channels of cloudscape at $SIZE_HD through the daemon | 60 Hz | not measured (see the log) | - |"
fi
sub4=$(sed -n 's/^ *4 subscribers, 640x480 raw at 60 Hz asked: *\([0-9.]*\) fps each.*/\1/p' "$work/daemon_bench.out" 2>/dev/null)
if [[ -n $sub4 ]]; then
  echo "| daemon_bench: 4 subscribers of one 640x480 cumulus view (one render for all) | 60 Hz | $sub4 fps each$(status_of daemon_bench) | $(verdict "$sub4" '>=' 59) |"
else
  why="stopped before its subscriber figures"
  grep -q 'image files cannot be written' "$work/daemon_bench.out" 2>/dev/null && why="stopped at its PNG request (no image encoder in a bundle)"
  echo "| daemon_bench: 4 subscribers of one 640x480 cumulus view | 60 Hz | not measured: $why$(status_of daemon_bench) | - |"
fi

pipelined=$(sed -n 's/.*three overlapped stages.*at most \([0-9.]*\) samples\/s.*/\1/p' "$work/dataset.out" | head -1)
serial=$(sed -n 's/.*one thread: \([0-9.]*\) samples\/s.*/\1/p' "$work/dataset.out" | head -1)
png=$(sed -n 's/.* PNG \([0-9.]*\) ms, mask PNG \([0-9.]*\) ms.*/\1 + \2/p' "$work/dataset.out" | head -1)
if [[ -n $pipelined ]]; then
  echo "| example dataset (EXAMPLE.toml, $SAMPLES samples) | >= 150 samples/s | $pipelined samples/s pipelined (slowest stage), $serial on one thread; PNG + mask PNG $png ms a sample$( [[ $mode == bundle ]] && echo ' (not encoded in a bundle)')$(status_of dataset) | $(verdict "$pipelined" '>=' 150) |"
else
  echo "| example dataset (EXAMPLE.toml) | >= 150 samples/s | not measured$(status_of dataset) | - |"
fi

daemon_mem=$(sed -n 's/^daemon memory at the end: //p' "$work/daemon.out")
echo "| memory | (recorded) | genus_bench peak ${mem_hd:-?} MiB at $SIZE_HD, ${mem_uhd:-?} MiB at $SIZE_UHD; daemon with 4 channels: ${daemon_mem:-?}; sampled peaks $(cat "$work/dataset.mem" 2>/dev/null || echo ?) (dataset), $(cat "$work/daemon_bench.mem" 2>/dev/null || echo ?) (daemon_bench) | - |"
echo
echo "total ${SECONDS} s; log: $LOG"
exec 1>&- 2>&-
wait "$tee_pid" 2>/dev/null || true

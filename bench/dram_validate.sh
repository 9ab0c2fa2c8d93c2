#!/bin/sh
# raypipe's DRAM model against DRAMsim3 (docs/hw-model.md, "DRAM validated against
# DRAMsim3"): the same request streams replayed on both, DDR3-1600 and DDR4-2400 —
# five synthetic streams at half and at full peak load, then the requests of one frame
# (saarcor preset, 512×384, kd-tree, primary rays) of the conference room, the Stanford
# bunny and Sponza, recorded with `simulate --memory-trace` on raypipe's DRAM. Prints the
# Markdown table; then the same frames simulated in closed loop on both memories (the
# DRAM model set to DRAMsim3's DDR3-1600 file, no controller latency): frame cycles. Needs cmake (DRAMsim3 is built by the dramsim3 crate) and the scenes
# under $RAYPIPE_SCENES (default scenes/; docs/scenes.md says where to download them).
#
#   bench/dram_validate.sh [OUT]       (default OUT: dram-validate-out)
set -eu
here=$(cd "$(dirname "$0")" && pwd)
out=${1:-dram-validate-out}
mkdir -p "$out"
manifest="$here/../Cargo.toml"
cargo build --release --quiet --manifest-path "$manifest" -p raypipe-hw --features dramsim3 --example dram_validate
cargo build --release --quiet --manifest-path "$manifest" -p raypipe --features dramsim3
rp="$here/../target/release/raypipe"
dv="$here/../target/release/examples/dram_validate"
scenes=${RAYPIPE_SCENES:-$here/../scenes}
rows="$out/rows.jsonl"
: >"$rows"
for memory in ddr3 ddr4; do
    for stream in sequential random strided row-conflict read-write; do
        # 64 bytes every 8 memory cycles is half the channel's peak; every 4, all of it.
        for interval in 8 4; do
            "$dv" "$memory" "$stream" "$interval" | sed "s/\"stream\":\"$stream\"/\"stream\":\"$stream @1\/$interval\"/" >>"$rows"
        done
    done
done
for scene in conference/conference.obj.gz:conference stanford_bunny/stanford-bunny.obj:bunny \
    sponza_dabrovic/sponza.obj.gz:sponza; do
    path=$scenes/${scene%%:*}
    name=${scene##*:}
    [ -f "$path" ] || { echo "skipping $name: $path not found" >&2; continue; }
    camera="$here/../fixtures/cameras/$name.camera"
    cam=""
    [ -f "$camera" ] && cam="--camera $camera"
    # shellcheck disable=SC2086
    "$rp" simulate "$path" $cam --size 512x384 --preset saarcor --accel kd --set memory.model=dram \
        --memory-trace "$out/$name.trace" -o "$out/$name.png" --report "$out/$name.json" >/dev/null
    for memory in ddr3 ddr4; do
        "$dv" "$memory" "$out/$name.trace" 533 | sed "s|\"stream\":\"[^\"]*\"|\"stream\":\"$name frame\"|" >>"$rows"
    done
done
ddr3="--set memory.dram.clock_mhz=800 --set memory.dram.t_rcd=11 --set memory.dram.t_rp=11 --set memory.dram.t_cl=11
 --set memory.dram.t_cwl=8 --set memory.dram.t_wtr=6
 --set memory.dram.t_ras=28 --set memory.dram.t_wr=12 --set memory.dram.t_refi=6240 --set memory.dram.t_rfc=208
 --set memory.dram.t_rrd=5 --set memory.dram.t_faw=24 --set memory.dram.controller_latency=0
 --set memory.dram.ranks=2 --set memory.dram.t_rtrs=1
 --set memory.dramsim3.config=DDR3_4Gb_x8_1600"
for name in conference bunny sponza; do
    [ -f "$out/$name.json" ] || continue
    path=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['run']['scene'])" "$out/$name.json")
    camera="$here/../fixtures/cameras/$name.camera"
    cam=""
    [ -f "$camera" ] && cam="--camera $camera"
    for m in dram dramsim3; do
        # shellcheck disable=SC2086
        "$rp" simulate "$path" $cam --size 512x384 --preset saarcor --accel kd $ddr3 --set memory.model=$m \
            -o "$out/$name-$m.png" --report "$out/$name-$m.json" --quiet >/dev/null
    done
done
python3 - "$rows" <<'PY'
import json, sys
print("| memory | stream | mean latency ns (raypipe / DRAMsim3) | p99 ns | bandwidth GB/s | row hits |")
print("|---|---|---|---|---|---|")
for line in open(sys.argv[1]):
    r = json.loads(line)
    a, b = r["raypipe"], r["dramsim3"]
    def pair(k, f="{:.0f}"):
        x, y = a[k], b[k]
        ratio = f" ({x / y:.2f}×)" if y else ""
        return f"{f.format(x)} / {f.format(y)}{ratio}"
    mem = {"ddr3": "DDR3-1600", "ddr4": "DDR4-2400"}[r["memory"]]
    print(f"| {mem} | {r['stream']} | {pair('mean_ns')} | {pair('p99_ns')} | "
          f"{pair('bandwidth_gb_s', '{:.2f}')} | {a['row_hit_rate']:.1%} / {b['row_hit_rate']:.1%} |")
import os
out = os.path.dirname(sys.argv[1])
print()
print("| frame (saarcor, DDR3-1600) | cycles: dram / dramsim3 | row hits | achieved / largest bound |")
print("|---|---|---|---|")
for name in ["conference", "bunny", "sponza"]:
    try:
        a = json.load(open(f"{out}/{name}-dram.json"))
        b = json.load(open(f"{out}/{name}-dramsim3.json"))
    except OSError:
        continue
    ra, rb = a["memory"]["dram"]["row_hit_rate"], b["memory"]["dramsim3"]["row_hit_rate"]
    print(f"| {name} | {a['cycles']} / {b['cycles']} ({a['cycles'] / b['cycles']:.2f}×) | {ra:.1%} / {rb:.1%} | "
          f"{a['bounds']['achieved_over_largest']:.2f} ({a['bounds']['largest']}) / "
          f"{b['bounds']['achieved_over_largest']:.2f} ({b['bounds']['largest']}) |")
PY

#!/usr/bin/env bash
# One sitting, alternated: ref = 4319efa (the 26 Nov 20:00 sitting's "after": enqueue 1,016-1,118/s, offline 12.0-12.2 ms then),
# before = 3f45c5a (this session's start), after = main (installed sources).
cd /work/main
out=/work/measure-$(date +%H%M); mkdir -p $out
pp() { local d=$1; echo "$d/rosaos-core/src:$d/plugins/rosaos-reachy/src:$d/plugins/rosaos-ros/src:$d/plugins/rosaos-spotify/src:$d/plugins/rosaos-tapo/src"; }
REF=$(pp /work/before-4319efa); BEF=$(pp /work/before-3f45c5a)
for i in 1 2; do
  uptime >> $out/load.txt
  PYTHONPATH=$BEF timeout 300 .venv/bin/python benchmarks/footprint.py --runs 1 > $out/fp-before-$i.txt 2>&1
  timeout 300 .venv/bin/python benchmarks/footprint.py --runs 1 > $out/fp-after-$i.txt 2>&1
done
for i in 1 2 3; do
  uptime >> $out/load.txt
  PYTHONPATH=$REF timeout 300 .venv/bin/python benchmarks/offline_command.py --runs 40 > $out/oc-ref-$i.txt 2>&1
  PYTHONPATH=$BEF timeout 300 .venv/bin/python benchmarks/offline_command.py --runs 40 > $out/oc-before-$i.txt 2>&1
  timeout 300 .venv/bin/python benchmarks/offline_command.py --runs 40 > $out/oc-after-$i.txt 2>&1
  PYTHONPATH=$REF timeout 300 .venv/bin/python benchmarks/kernel.py --only throughput --events 2000 > $out/kt-ref-$i.txt 2>&1
  PYTHONPATH=$BEF timeout 300 .venv/bin/python benchmarks/kernel.py --only throughput --events 2000 > $out/kt-before-$i.txt 2>&1
  timeout 300 .venv/bin/python benchmarks/kernel.py --only throughput --events 2000 > $out/kt-after-$i.txt 2>&1
done
uptime >> $out/load.txt
echo $out

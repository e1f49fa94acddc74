#!/usr/bin/env bash
# `confpack sweep --slurm --submit` against a live Slurm: a one-node cluster on this host (munged,
# slurmctld, slurmd from Debian's slurm-wlm and munge), started here as root and stopped by the
# daemons' own PIDs whatever the outcome. Run by ctest (label slurm): tests/CMakeLists.txt.
#
#   1. A study of 6 short runs submitted with --slurm --submit; the task of the longest run is
#      cancelled with scancel while it runs; --status says it failed and why. Every other run
#      finished exactly once.
#   2. One finished run's result deleted; submitted again: the script holds exactly the cancelled
#      run and the deleted one, those two run again (no other), and `confpack report` builds.
#   3. A study with a run whose configuration cannot be deposited (a gap narrower than a grain):
#      its task fails, and --status shows the run failed with the deposition's reason.
#
# Usage: test_slurm_cluster.sh CONFPACK_BINARY, as root (or through password-less sudo). Fails,
# never skips, when Slurm does not come up.
set -euo pipefail

confpack=$(realpath "$1")
started=$SECONDS
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
if [[ $(id -u) -ne 0 ]]; then
  # As .ci/run does for apt-get outside root: through password-less sudo when there is one.
  if sudo -n true 2> /dev/null; then exec sudo -n bash "$0" "$@"; fi
  fail "must run as root or with password-less sudo (munged --force, slurmd as SlurmdUser=root)"
fi
for p in munged slurmctld slurmd sbatch squeue scancel sinfo; do
  command -v "$p" > /dev/null || fail "$p not found (Debian: apt-get install slurm-wlm munge)"
done

tmp=$(mktemp -d /tmp/confpack-slurm.XXXXXX)
munged_pid='' ctld_pid='' slurmd_pid=''
stop() {  # PID: SIGTERM, then SIGKILL after 10 s
  [[ -n "$1" ]] || return 0
  kill "$1" 2> /dev/null || return 0
  for _ in $(seq 100); do kill -0 "$1" 2> /dev/null || return 0; sleep 0.1; done
  kill -KILL "$1" 2> /dev/null || true
}
cleanup() {
  local rc=$?
  trap - EXIT
  if [[ -n "$ctld_pid" ]]; then timeout 10 scancel --quiet --user=root 2> /dev/null || true; fi
  stop "$slurmd_pid"
  stop "$ctld_pid"
  stop "$munged_pid"
  if [[ $rc -ne 0 ]]; then
    for log in slurmctld.out slurmctld.log slurmd.out slurmd.log munged.out munged.log; do
      [[ -f "$tmp/$log" ]] && { echo "--- $log (last lines)"; tail -n 15 "$tmp/$log"; }
    done
    for log in "$tmp"/*/slurm/logs/*.out; do [[ -f "$log" ]] && { echo "--- $log"; tail -n 5 "$log"; }; done
  fi
  rm -rf "$tmp"
  echo "slurm test: exit $rc after $((SECONDS - started)) s"
  exit $rc
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# --- the cluster -----------------------------------------------------------------------------
# A port nobody listens on (bash's /dev/tcp: no other tool needed).
free_port() {
  local p
  while :; do
    p=$((20000 + RANDOM % 20000))
    (exec 3<> "/dev/tcp/127.0.0.1/$p") 2> /dev/null || { echo "$p"; return; }
  done
}
mkdir -p "$tmp/state" "$tmp/spool"
dd if=/dev/urandom of="$tmp/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge.key"
munged --foreground --force --key-file="$tmp/munge.key" --socket="$tmp/munge.socket" \
  --pid-file="$tmp/munged.pid" --seed-file="$tmp/munged.seed" --log-file="$tmp/munged.log" \
  < /dev/null > "$tmp/munged.out" 2>&1 &
munged_pid=$!
ctld_port=$(free_port)
slurmd_port=$(free_port)
[[ "$ctld_port" != "$slurmd_port" ]] || slurmd_port=$((ctld_port + 1))
# This machine as slurmd sees it: NodeName=HOST CPUs=... RealMemory=...; reached at 127.0.0.1,
# so that a host name missing from DNS or /etc/hosts does not matter.
node=$(slurmd -C | head -n 1)
[[ "$node" == NodeName=* ]] || fail "slurmd -C printed no node line: $node"
host=${node#NodeName=}
host=${host%% *}
cat > "$tmp/slurm.conf" << EOF
ClusterName=confpacktest
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge.socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/builtin
MpiDefault=none
ReturnToService=2
KillWait=5
MinJobAge=600
$node NodeAddr=127.0.0.1 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF="$tmp/slurm.conf"
for _ in $(seq 50); do [[ -S "$tmp/munge.socket" ]] && break; sleep 0.1; done
[[ -S "$tmp/munge.socket" ]] || fail "munged did not start: $(cat "$tmp/munged.out")"
# In the foreground (-D) so that $! is the daemon's own PID; their output goes to files, not to
# ctest's pipe, which would otherwise stay open while they live.
slurmctld -D < /dev/null > "$tmp/slurmctld.out" 2>&1 &
ctld_pid=$!
slurmd -D < /dev/null > "$tmp/slurmd.out" 2>&1 &
slurmd_pid=$!
up='' deadline=$((SECONDS + 30))
while ((SECONDS < deadline)); do
  if [[ "$(timeout 5 sinfo --noheader --format=%T 2> /dev/null)" == idle ]]; then up=1; break; fi
  sleep 0.5
done
[[ -n "$up" ]] || fail "Slurm did not come up in 30 s (sinfo: $(timeout 5 sinfo 2>&1 | tr '\n' ' ' || echo no answer))"
echo "slurm: up in $((SECONDS - started)) s (slurmctld $ctld_pid, slurmd $slurmd_pid, munged $munged_pid)"

# --- helpers ---------------------------------------------------------------------------------
# Waits until Slurm lists no job of array JOB (at most $2 s).
wait_job() {
  for _ in $(seq $(($2 * 5))); do
    [[ -z "$(squeue --noheader --jobs="$1" --format=%i 2> /dev/null)" ]] && return 0
    sleep 0.2
  done
  squeue
  fail "job $1 still listed after $2 s"
}
# The job id from `confpack sweep ... --submit`'s line "submitted job N: ...".
job_of() { sed -n 's/^submitted job \([0-9]*\):.*/\1/p' <<< "$1"; }
# How often run R finished (its progress line "[k/n] R nscd ...") in the logs of sweep folder D.
times_run() { cat "$1"/slurm/logs/*.out | grep -c "^\[[0-9]*/[0-9]*\] $2 " || true; }
status_of() { "$confpack" sweep "$1" --status | awk -v r="$2" '$1 == r'; }

cd "$tmp"
# 6 runs of 80 to 100 spheres, one deposit each, 1 t0 of compaction (well under a second);
# r0005 compacts until it is at rest (some seconds), so that it is still running when cancelled.
cat > study.json << 'EOF'
{ "name": "slurm-test",
  "base": { "box": { "length_x": 3, "height": 7 }, "compaction": { "time_limit": 1 } },
  "groups": [ { "width": [3, 3.25, 3.5, 3.75, 4], "backend": "nscd" },
              { "width": [4.25], "backend": "nscd", "compaction.time_limit": [60] } ] }
EOF

# --- 1. submit, cancel one task mid-run ------------------------------------------------------
out=$("$confpack" sweep study.json --out study --slurm --submit --time 5 --cpus-per-task 1 --mem 200M \
  --sbatch-line=--job-name=cp-test)
echo "$out"
job=$(job_of "$out")
[[ -n "$job" ]] || fail "no job id in: $out"
grep -q '^#SBATCH --array=0-5$' study/slurm/study.sbatch || fail "expected 6 array tasks: $(cat study/slurm/study.sbatch)"
# r0005 is task 5: cancel it as soon as it holds its run, then the status says it is running first.
for _ in $(seq 300); do [[ -f study/claims/r0005 ]] && break; sleep 0.1; done
[[ -f study/claims/r0005 ]] || fail "r0005 never started"
line=$(status_of study r0005)
[[ "$line" == *" running  ${job}_5 "* ]] || fail "r0005 should be running in ${job}_5: $line"
scancel "${job}_5"
wait_job "$job" 90
"$confpack" sweep study --status
line=$(status_of study r0005)
[[ "$line" == *" failed "*"${job}_5"* ]] || fail "the cancelled r0005 should show failed: $line"
[[ "$line" == *CANCELLED* || "$line" == *interrupted* || "$line" == *stopped* ]] ||
  fail "the cancelled run's reason should say so: $line"
[[ ! -f study/claims/r0005 ]] || fail "the cancelled task left its claim"
for r in r0000 r0001 r0002 r0003 r0004; do
  [[ -f study/runs/$r/done.json ]] || fail "$r not done after the first array"
  [[ $(times_run study $r) -eq 1 ]] || fail "$r finished $(times_run study $r) times in the first array"
done
[[ ! -f study/runs/r0005/done.json ]] || fail "r0005 finished although cancelled"

# --- 2. one result deleted: resubmit, only the two unfinished runs run --------------------------
rm -rf study/runs/r0002
sums=$(md5sum study/runs/r000[0134]/done.json)
out=$("$confpack" sweep study.json --out study --slurm --submit --time 5)
echo "$out"
job2=$(job_of "$out")
[[ -n "$job2" ]] || fail "no job id in: $out"
grep -q '^#SBATCH --array=0-1$' study/slurm/study.sbatch || fail "expected 2 array tasks: $(cat study/slurm/study.sbatch)"
[[ "$(sed -n '/^runs=(/,/^)/p' study/slurm/study.sbatch | tr -d ' \n')" == "runs=(r0002r0005)" ]] ||
  fail "the second array should hold r0002 and r0005 only: $(cat study/slurm/study.sbatch)"

# --- 3. meanwhile, a study whose second run cannot be deposited -------------------------------
cat > bad.json << 'EOF'
{ "name": "slurm-bad", "base": { "box": { "length_x": 3, "height": 3 }, "compaction": { "time_limit": 0.5 } },
  "vary": { "width": [3, 0.5], "backend": "nscd" } }
EOF
out=$("$confpack" sweep bad.json --out bad --slurm --submit --time 5)
echo "$out"
job3=$(job_of "$out")
[[ -n "$job3" ]] || fail "no job id in: $out"

wait_job "$job2" 90
wait_job "$job3" 60
"$confpack" sweep study --status
for r in r0000 r0001 r0002 r0003 r0004 r0005; do
  [[ -f study/runs/$r/done.json ]] || fail "$r not done after the second array"
done
md5sum --quiet --check <<< "$sums" || fail "a run finished in the first array was redone"
# Finished: r0002 twice (its result was deleted), every other run once (r0005's first try was
# cut short: it printed no line).
for r in r0000 r0001 r0003 r0004 r0005; do
  [[ $(times_run study $r) -eq 1 ]] || fail "$r finished $(times_run study $r) times"
done
[[ $(times_run study r0002) -eq 2 ]] || fail "r0002 finished $(times_run study r0002) times (twice expected)"
"$confpack" sweep study --status | grep -q '^6 runs: 6 done, 0 running, 0 queued, 0 failed, 0 missing$' ||
  fail "the status should count 6 runs done"
"$confpack" report study --no-figures || fail "confpack report failed"
grep -q '6 done' study/report/report.md || fail "the report should count 6 runs done: $(head -20 study/report/report.md)"

"$confpack" sweep bad --status
[[ -f bad/runs/r0000/done.json ]] || fail "the good run of the bad study should be done"
line=$(status_of bad r0001)
[[ "$line" == *" failed "*"${job3}_1"*"narrower than the placeholder diameter"* ]] ||
  fail "r0001 of the bad study should show failed with the deposition's reason: $line"
echo "slurm test: passed in $((SECONDS - started)) s"

# Sourced by the CI scripts that run a gtest program in several processes side by side.
#
# run_gtest_shards SHARDS LOG-PREFIX COMMAND...: runs COMMAND (a gtest program and its
# arguments, or a launcher of it) as SHARDS processes at once, process i with gtest's
# GTEST_TOTAL_SHARDS=SHARDS and GTEST_SHARD_INDEX=i, so each runs its own share of the tests,
# and its output in LOG-PREFIX-i.log (the logs of an earlier run, of any shard count, are
# removed first). Waits for all; sets failed_shards to the indices of those that exited
# non-zero.
run_gtest_shards() {
  local shards="$1" prefix="$2"
  shift 2
  rm -f "$prefix"-*.log
  local pids=() shard
  for shard in $(seq 0 $((shards - 1))); do
    GTEST_TOTAL_SHARDS="$shards" GTEST_SHARD_INDEX="$shard" "$@" >"$prefix-$shard.log" 2>&1 &
    pids+=($!)
  done
  failed_shards=()
  for shard in $(seq 0 $((shards - 1))); do
    wait "${pids[$shard]}" || failed_shards+=("$shard")
  done
}

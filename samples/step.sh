# Sourced by the scripts that check an installed SDK (check_installed_sdk.sh,
# test_installed_sdk.sh, packaging/scripts/deb.sh).
# step NAME CMD...: runs CMD with its output in $work/NAME.log; on failure shows the log's end.
step() {
  local name=$1
  shift
  if ! "$@" > "$work/$name.log" 2>&1; then
    echo "FAIL: $name: $*" >&2
    tail -n 60 "$work/$name.log" >&2
    exit 1
  fi
}

#!/usr/bin/env bash
# Installs the client component into a scratch prefix, builds the example
# controller from there with pkg-config only, and runs it against a missing
# segment (it must report "no daemon", exit 3); the installed Python module
# must load the installed library by its soname and say NOT_FOUND too.
set -euo pipefail
build_dir=$1
source_file=$2
prefix=$(mktemp -d)
trap 'rm -rf "$prefix"' EXIT
cmake --install "$build_dir" --prefix "$prefix" --component client >/dev/null
pc_dir=$(dirname "$(find "$prefix" -name ceilpose-client.pc)")
for f in include/ceilpose/pose_client.h; do
  test -f "$prefix/$f" || { echo "missing $f in the install"; exit 1; }
done
test -n "$(find "$prefix" -name libceilpose_client.so.3)" ||
  { echo "libceilpose_client.so.3 not installed"; exit 1; }
flags=$(PKG_CONFIG_PATH=$pc_dir pkg-config --cflags --libs ceilpose-client)
cc -std=c11 -Wall -Wextra -Wpedantic -Werror "$source_file" $flags -o "$prefix/printer"
libdir=$(PKG_CONFIG_PATH=$pc_dir pkg-config --variable=libdir ceilpose-client)
set +e
LD_LIBRARY_PATH=$libdir "$prefix/printer" --shm "/ceilpose-install-test-$$" 2>"$prefix/err"
rc=$?
set -e
grep -q "ceilpose-install-test" "$prefix/err" || { cat "$prefix/err"; exit 1; }
test "$rc" -eq 3 || { echo "expected exit 3, got $rc"; exit 1; }
py_dir=$prefix/lib/python3/dist-packages
test -f "$py_dir/ceilpose/__init__.py" || { echo "ceilpose Python module not installed"; exit 1; }
env -u CEILPOSE_CLIENT_LIBRARY LD_LIBRARY_PATH=$libdir PYTHONPATH=$py_dir PYTHONDONTWRITEBYTECODE=1 \
  python3 -c '
import ceilpose
try:
    ceilpose.Client("/ceilpose-install-test-py")
except ceilpose.CeilposeError as e:
    assert e.name == "NOT_FOUND", e
    print("python:", e)
else:
    raise SystemExit("expected NOT_FOUND")
' || { echo "installed Python module does not work"; exit 1; }
echo "ok: installed client builds with pkg-config and runs; the Python module loads it"

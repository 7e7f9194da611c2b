# Sourced by the tests here: strict mode, the pipeloc binary ($1) as $bin, the repository as $here,
# a scratch folder $work removed on exit, and fail MESSAGE.
set -euo pipefail
bin="$1"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

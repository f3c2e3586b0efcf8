#!/usr/bin/env bash
# The container image end to end (label `container`; not in the default run: building the image
# takes minutes). Builds it with scripts/container-image (layers are reused when nothing changed),
# then runs it as a user would: /readyz answers 200 through the published port, the healthcheck
# passes, the daemon runs as a non-root user, an upload through the port completes, and the dataset
# and its tiles survive a restart of the container (podman stop sends SIGTERM: a clean stop, exit 0).
#   tests/container/container_test.sh [IMAGE]
set -euo pipefail
cd "$(dirname "$0")/../.."
image="${1:-localhost/pointdag:test}"
data="${POINTDAG_DATA_DIR:-../shared/data}"
scan="$data/tiny_1.2-with-color_1065pts.las"
[ -f "$scan" ] || { echo "container_test: $scan not found (set POINTDAG_DATA_DIR): cannot upload a real scan" >&2; exit 1; }
scripts/container-image "$image" >/dev/null

podman=(podman --runtime=runc)
name="pointdag-test-$$"
volume="pointdag-test-$$"
token="container-test-token"
port=$((20000 + $$ % 20000))
cleanup() {
  "${podman[@]}" rm -f "$name" >/dev/null 2>&1 || true
  "${podman[@]}" volume rm -f "$volume" >/dev/null 2>&1 || true
}
trap cleanup EXIT
fail() { echo "container_test: FAIL: $*" >&2; "${podman[@]}" logs "$name" >&2 || true; exit 1; }

"${podman[@]}" volume create "$volume" >/dev/null
"${podman[@]}" run -d --name "$name" -p "127.0.0.1:$port:8080" -e POINTDAGD_TOKEN="$token" \
  -v "$volume:/var/lib/pointdag" --ulimit nofile=20000:20000 --ulimit nproc=32768:32768 "$image" >/dev/null

url="http://127.0.0.1:$port"
ready() {
  for _ in $(seq 1 120); do
    [ "$(curl -s -o /dev/null -w '%{http_code}' "$url/readyz")" = 200 ] && return 0
    sleep 0.5
  done
  return 1
}
ready || fail "/readyz never answered 200"
"${podman[@]}" healthcheck run "$name" >/dev/null || fail "the healthcheck failed"
uid="$("${podman[@]}" exec "$name" id -u)"
[ "$uid" != 0 ] || fail "pointdagd runs as root"

# Writes need the token from the environment.
code="$(curl -s -o /dev/null -w '%{http_code}' --data-binary "@$scan" "$url/v1/datasets?name=tiny")"
[ "$code" = 401 ] || fail "an upload without the token answered $code, not 401"
location="$(curl -s -D - -o /dev/null -H "Authorization: Bearer $token" --data-binary "@$scan" "$url/v1/datasets?name=tiny" |
            tr -d '\r' | sed -n 's/^[Ll]ocation: //p')"
[ -n "$location" ] || fail "the upload was not accepted"
dataset=""
for _ in $(seq 1 240); do
  job="$(curl -s "$url$location")"
  case "$job" in
    *'"status": "done"'*) dataset="$(sed -n 's/.*"dataset_id": "\([0-9a-f]*\)".*/\1/p' <<<"$job")"; break ;;
    *'"status": "failed"'*) fail "the ingest failed: $job" ;;
  esac
  sleep 0.5
done
[ -n "$dataset" ] || fail "the ingest did not finish: $job"
tile_before="$(curl -s "$url/v1/datasets/$dataset/tiles/0/0/0/0" | sha256sum)"

"${podman[@]}" stop -t 30 "$name" >/dev/null
exit_code="$("${podman[@]}" inspect --format '{{.State.ExitCode}}' "$name")"
[ "$exit_code" = 0 ] || fail "SIGTERM ended pointdagd with exit code $exit_code, not 0"
"${podman[@]}" start "$name" >/dev/null
ready || fail "/readyz never answered 200 after the restart"
[ "$(curl -s -o /dev/null -w '%{http_code}' "$url/v1/datasets/$dataset")" = 200 ] || fail "the dataset is gone after a restart"
tile_after="$(curl -s "$url/v1/datasets/$dataset/tiles/0/0/0/0" | sha256sum)"
[ "$tile_before" = "$tile_after" ] || fail "the tile changed across the restart"
echo "container_test: ok ($image: ready, healthy, uid $uid, upload $location -> dataset $dataset, stopped with exit 0, kept across the restart)"

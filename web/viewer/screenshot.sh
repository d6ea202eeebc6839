#!/usr/bin/env bash
# A screenshot of the viewer's page in Debian's headless Chromium (how docs/viewer.png is made):
#   web/viewer/screenshot.sh URL OUT.png [WAIT_S] [WIDTHxHEIGHT]
# Starts chromedriver on a free local port, opens URL, waits WAIT_S seconds (default 10) and writes
# the picture. Run it where the viewer is reachable (inside the graph's network namespace for
# make demo's live graph, or anywhere for lanemap-viewer --store). Needs chromium, chromium-driver, curl.
set -euo pipefail
url=$1 out=$2 wait_s=${3:-10} size=${4:-1400x900}
port=$((20000 + RANDOM % 20000))
profile=$(mktemp -d "${TMPDIR:-/tmp}/lanemap-shot.XXXXXX")
chromedriver --port="$port" > "$profile/chromedriver.log" 2>&1 &
driver=$!
trap 'kill $driver 2> /dev/null || true; rm -rf "$profile"' EXIT
api="http://127.0.0.1:$port"
for _ in $(seq 1 50); do curl -sf -o /dev/null "$api/status" && break; sleep 0.2; done
caps='{"capabilities":{"alwaysMatch":{"browserName":"chrome","goog:chromeOptions":{"binary":"/usr/bin/chromium","args":["--headless=new","--no-sandbox","--disable-gpu","--disable-dev-shm-usage","--window-size='${size/x/,}'","--user-data-dir='$profile/p'"]}}}}'
session=$(curl -sf -X POST -H 'Content-Type: application/json' -d "$caps" "$api/session" | sed -e 's/.*"sessionId":"\([^"]*\)".*/\1/')
curl -sf -X POST -H 'Content-Type: application/json' -d "{\"url\":\"$url\"}" "$api/session/$session/url" > /dev/null
sleep "$wait_s"
curl -sf "$api/session/$session/screenshot" | sed -e 's/.*"value":"\([^"]*\)".*/\1/' | base64 -d > "$out"
curl -sf -X DELETE "$api/session/$session" > /dev/null || true
echo "screenshot: $out"

#!/bin/sh
# The REST API over HTTPS with bearer tokens against the gateway on real
# SocketCAN (issue 6): canopen-sim devices on vcan0; every route of the
# contract with its role (rest_client.py), typed SDO round trip, 422 with the
# abort code, 504, 400, 404, 429; NMT stop and an admin's reset; WSS events
# with ?access_token=; plain HTTP refused on the TLS port; MQTT requests
# checked with the same tokens; audit lines for writes and refusals. Issue 12:
# cross-site writes, DNS rebinding, cross-site WebSocket, request smuggling
# and one address hogging connections are refused (hostile_client.py).
# uml-run: --timeout 220
. "$(dirname "$0")/lib.sh"
GW=gw1
DIR=$(dirname "$0")

# A throw-away CA-less certificate for 127.0.0.1 (EC: quick to make in UML).
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes -days 1 -subj "/CN=127.0.0.1" \
  -addext "subjectAltName=IP:127.0.0.1" -keyout "$T/key.pem" -out "$T/cert.pem" > "$T/openssl.log" 2>&1 ||
  fail "openssl: $(cat "$T/openssl.log")"
VIEWER=viewer-$$-secret OPERATOR=operator-$$-secret ADMIN=admin-$$-secret
export VIEWER OPERATOR ADMIN
hash() { printf %s "$1" | sha256sum | cut -d' ' -f1; }

start_mosquitto
mosquitto_sub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -v -t "reply/#" -F '%t %P %p' > "$T/replies.log" 2>&1 &
sleep 0.3
cat > "$T/gw.yaml" <<YAML
gateway: {id: $GW, state-dir: $T/state}
networks:
  - interface: vcan0
    heartbeat-ms: 500
    nodes:
      - {id: 5, eds: $EDS_DIR/cia402-drive.eds, heartbeat-consumer-ms: 1000, boot: {start: true}}
      - {id: 10, eds: $EDS_DIR/cia401-io-module.eds, heartbeat-consumer-ms: 1000, boot: {start: true}}
mqtt:
  uri: tcp://127.0.0.1:$MOSQ_PORT
http:
  listen: 127.0.0.1:8443
  tls: {cert: $T/cert.pem, key: $T/key.pem}
  rate-limit: {requests-per-second: 0}
  # rest_client.py's 429 check holds 45 requests from 127.0.0.1 at once.
  max-connections-per-address: 48
  tokens:
    - {name: viewer, role: viewer, sha256: $(hash "$VIEWER")}
    - {name: operator, role: operator, sha256: $(hash "$OPERATOR")}
    - {name: admin, role: admin, sha256: $(hash "$ADMIN")}
YAML
start_gateway --config "$T/gw.yaml"
start_sim "$T/sim.log" --node 5="$EDS_DIR/cia402-drive.eds" --node 10="$EDS_DIR/cia401-io-module.eds" \
  --heartbeat 200 --tpdo-period 100
wait_for "$GW_LOG" "node 10 .*operational" 20
wait_for "$GW_LOG" "node 5 .*operational" 20

# Plain HTTP on the TLS port gets no HTTP answer.
/usr/bin/python3 -c 'import urllib.request; urllib.request.urlopen("http://127.0.0.1:8443/api/v1/gateway", timeout=5)' \
  > "$T/plain.out" 2>&1 && fail "plain HTTP was answered on the TLS port"
pass "plain HTTP refused on the HTTPS port: $(tail -1 "$T/plain.out")"

# Before rest_client.py: its 429 check leaves requests pending on 127.0.0.1.
/usr/bin/python3 "$DIR/hostile_client.py" 8443 "$T/cert.pem" 48 > "$T/hostile.log" 2>&1 ||
  fail "hostile checks: $(tail -5 "$T/hostile.log")"
[ "$(grep -c "client 127.0.0.1 has 48 connections open" "$GW_LOG")" -eq 0 ] ||
  fail "idle connections at the address cap were refused instead of making room"
pass "cross-site writes (403/415), rebinding (421), cross-site WebSocket (403), smuggling (400) refused;" \
  "one address at its connection cap is not locked out, nor is another: $(grep -c '^ok:' "$T/hostile.log") checks"

/usr/bin/python3 "$DIR/rest_client.py" https://127.0.0.1:8443 "$T/cert.pem" > "$T/rest.log" 2>&1 ||
  fail "REST checks: $(tail -5 "$T/rest.log")"
pass "REST routes with roles over HTTPS: $(grep -c '^ok:' "$T/rest.log") checks"

# WSS with the token in the query (browsers cannot set WebSocket headers).
WS_CA=$T/cert.pem /usr/bin/python3 "$DIR/ws_client.py" 127.0.0.1 8443 '{"nodes":[5],"kinds":["tpdo"]}' 3 \
  "/api/v1/events?access_token=$VIEWER" > "$T/ws.log" 2>&1 || fail "WSS client: $(cat "$T/ws.log")"
WS_CA=$T/cert.pem /usr/bin/python3 "$DIR/ws_client.py" 127.0.0.1 8443 '{}' 1 > "$T/ws-anon.log" 2>&1 &&
  fail "WSS without a token was accepted"
grep -q "401" "$T/ws-anon.log" || fail "WSS without a token: $(cat "$T/ws-anon.log")"
pass "WSS events with access_token; 401 without"

# MQTT requests: tokens are configured, so a request needs one.
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/10/sdo/write" \
  -m '{"index": "1017", "subIndex": 0, "value": 300}' -D publish response-topic reply/anon
wait_for "$T/replies.log" '^reply/anon .*401' 10
mosquitto_pub -h 127.0.0.1 -p $MOSQ_PORT -V mqttv5 -t "canopen/$GW/1/10/sdo/write" \
  -m '{"index": "1017", "subIndex": 0, "value": 300}' -D publish response-topic reply/op \
  -D publish user-property authorization "Bearer $OPERATOR"
wait_for "$T/replies.log" '^reply/op .*"value": ?300' 10
pass "MQTT SDO write: 401 without a token, done with the operator's"

grep -q "audit: SDO write by operator@127.0.0.1: net 1 node 10 1017h sub 0 = 250: ok" "$GW_LOG" ||
  fail "no audit line for the REST SDO write"
grep -q "audit: NMT reset-node by admin@127.0.0.1: net 1 node 10: sent" "$GW_LOG" || fail "no audit line for the reset"
grep -q "audit: auth failure: operator@127.0.0.1: NMT reset-node net 1 node 10: 403" "$GW_LOG" ||
  fail "no audit line for the refused reset"
grep -q "audit: auth failure: anonymous@127.0.0.1: GET /api/v1/gateway: 401" "$GW_LOG" ||
  fail "no audit line for the missing token"
grep -q "audit: SDO write by operator: net 1 node 10 1017h sub 0 = 300: ok" "$GW_LOG" ||
  fail "no audit line for the MQTT SDO write"
grep -q "$OPERATOR" "$GW_LOG" && fail "a token reached the log"
pass "audit lines for writes, resets and refusals; no token in the log"
stop_gateway

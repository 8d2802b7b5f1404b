# Sourced by the bench scripts: start_broker DIR starts a mosquitto (no
# persistence, unlimited queue) on a free loopback port, waits until it
# answers, sets PORT and MOSQ, and stops it and removes DIR on exit.
start_broker() {
  local dir=$1
  PORT=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
  printf 'listener %s 127.0.0.1\nallow_anonymous true\npersistence false\nmax_queued_messages 0\n' "$PORT" > "$dir/m.conf"
  /usr/sbin/mosquitto -c "$dir/m.conf" > "$dir/m.log" 2>&1 &
  MOSQ=$!
  trap "kill $MOSQ 2>/dev/null; wait $MOSQ 2>/dev/null; rm -rf '$dir'" EXIT
  for _ in $(seq 50); do mosquitto_pub -h 127.0.0.1 -p "$PORT" -t probe -m x 2>/dev/null && break; sleep 0.1; done
}

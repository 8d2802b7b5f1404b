#!/usr/bin/env python3
"""The comparison for bench/mqtt_path.cpp: a straightforward python3-can +
paho-mqtt bridge doing the same job on the same frames (node 5 TPDO2:
Statusword u16 + Modes of operation display i8 -> JSON with seq, timestamp,
values -> MQTT at the same QoS), until the broker acknowledged every one.
Prints CPU per event (process time, all threads) and events per second.

usage: python_bridge.py HOST PORT EVENTS [QOS]
"""
import datetime
import json
import struct
import sys
import threading
import time

import can
import paho.mqtt.client as mqtt


def main():
    host, port, events = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    qos = int(sys.argv[4]) if len(sys.argv) > 4 else 1
    acked = 0
    done = threading.Event()
    lock = threading.Lock()

    def on_publish(_c, _u, _mid):
        nonlocal acked
        with lock:
            acked += 1
            if acked >= events:
                done.set()

    client = mqtt.Client(client_id="python-bridge-bench", protocol=mqtt.MQTTv311)
    client.max_inflight_messages_set(64)
    client.max_queued_messages_set(0)
    client.on_publish = on_publish
    client.connect(host, port)
    client.loop_start()
    frames = [can.Message(arbitration_id=0x285, data=bytes([i & 0xFF, (i >> 8) & 0xFF, 8]), is_extended_id=False)
              for i in range(events)]
    c0, t0 = time.process_time(), time.monotonic()
    for seq, msg in enumerate(frames, 1):
        statusword, mode = struct.unpack_from("<Hb", msg.data)
        payload = {
            "seq": str(seq),
            "timestamp": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="milliseconds"),
            "network": 1, "node": 5, "tpdo": 2, "cobId": msg.arbitration_id,
            "values": [
                {"index": 0x6041, "subIndex": 0, "name": "Statusword", "type": "u16", "value": statusword},
                {"index": 0x6061, "subIndex": 0, "name": "Modes of operation display", "type": "i8", "value": mode},
            ],
            "raw": msg.data.hex(),
        }
        client.publish("canopen/pybridge/1/5/tpdo/2", json.dumps(payload), qos=qos)
    if qos == 0:
        done.set()
    done.wait(120)
    c1, t1 = time.process_time(), time.monotonic()
    client.loop_stop()
    client.disconnect()
    print(f"events {events} acked {acked if qos else events} qos {qos}")
    print(f"python bridge CPU per event (all threads, until acked): {(c1 - c0) / events * 1e6:.2f} us")
    print(f"events per second to the broker: {events / (t1 - t0):.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

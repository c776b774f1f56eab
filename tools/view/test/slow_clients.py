#!/usr/bin/python3
"""Two clients of swf-view for the robustness test, run until the file STOP exists:
a slow browser (reads /events a few kilobytes at a time with pauses, so its stream backs up)
and a poller of /state.json (every 0.2 s: how many answers failed or were not valid JSON, and
whether the page ever called the publisher silent). Prints one JSON object at the end.

usage: slow_clients.py URL STOP
"""
import json
import os
import sys
import threading
import time
import urllib.request

url, stop = sys.argv[1], sys.argv[2]
result = {'polls': 0, 'poll_failures': 0, 'saw_silent': False, 'saw_live': False,
          'slow_bytes': 0, 'slow_events': 0}


def slow_browser():
    try:
        with urllib.request.urlopen(url + 'events', timeout=30) as r:
            while not os.path.exists(stop):
                chunk = r.read(4096)
                if not chunk:
                    break
                result['slow_bytes'] += len(chunk)
                result['slow_events'] += chunk.count(b'\nevent: ') + chunk.startswith(b'event: ')
                time.sleep(0.05)
    except OSError as e:
        result['slow_error'] = str(e)


t = threading.Thread(target=slow_browser, daemon=True)
t.start()
while not os.path.exists(stop):
    result['polls'] += 1
    try:
        with urllib.request.urlopen(url + 'state.json', timeout=5) as r:
            state = json.loads(r.read())
        publisher = state['status']['bus']['publisher']
        result['saw_silent'] |= publisher == 'silent'
        result['saw_live'] |= publisher == 'live'
    except (OSError, ValueError, KeyError) as e:
        result['poll_failures'] += 1
        result['last_failure'] = str(e)
    time.sleep(0.2)
print(json.dumps(result))

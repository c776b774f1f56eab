#!/usr/bin/python3
"""Loads swf-view's page in headless Chromium (through chromedriver's WebDriver HTTP interface,
no client library needed) and waits until the page itself shows what the test expects: the number
of navigation outputs, a navigation status, a hazard map with known cells (counted from the
canvas's pixels, not only from a label) and, when asked, a drawn image and tracked features. Saves a screenshot and
prints what the page showed as one JSON object. Exit 0 when everything was seen in time.

usage: page_check.py URL --frames N --screenshot OUT.png [--image] [--features] [--timeout S]
"""
import argparse
import base64
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request

# What the page shows, read from the DOM and from the hazard canvas's pixels (cells of a class
# other than "unknown", whose colour is #333).
PAGE_STATE = r"""
const text = (id) => (document.getElementById(id) || {textContent: null}).textContent;
const canvas = document.getElementById('hazard');
const data = canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
let known = 0;
for (let i = 0; i < data.length; i += 4) {
  if (data[i + 3] && !(data[i] === 0x33 && data[i + 1] === 0x33 && data[i + 2] === 0x33)) ++known;
}
const image = document.getElementById('image');
const px = image.getContext('2d').getImageData(0, 0, image.width, image.height).data;
let lit = 0;
for (let i = 0; i < px.length; i += 4) if (px[i] > 0) ++lit;
return {frames: text('frames'), status: text('nav-status'), hazard_frame: text('hazard-frame'),
        hazard_known_label: text('hazard-known'), hazard_known_pixels: known,
        safe_site: text('safe-site'), image_seq: text('image-seq'), image_lit_pixels: lit,
        landmarks: text('landmark-count'), connection: text('connection'),
        publisher: text('publisher'), malformed: text('malformed-total'), lost: text('lost-total'),
        features_frame: text('features-frame'), features_tracked: text('features-tracked'),
        features_new: text('features-new'), features_rejected: text('features-rejected'),
        features_gated: text('features-gated')};
"""


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


def call(base, method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers={'Content-Type': 'application/json'})
    with urllib.request.urlopen(req, timeout=60) as r:
        return json.loads(r.read())['value']


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('url')
    ap.add_argument('--frames', type=int, required=True)
    ap.add_argument('--screenshot', required=True)
    ap.add_argument('--image', action='store_true', help='require a drawn image')
    ap.add_argument('--features', action='store_true', help='require tracked features')
    ap.add_argument('--timeout', type=float, default=120)
    a = ap.parse_args()

    driver = shutil.which('chromedriver')
    if driver is None:
        print('page_check: chromedriver not found (Debian package chromium-driver)', file=sys.stderr)
        return 1
    port = free_port()
    profile = tempfile.mkdtemp(prefix='swf-view-chrome-')
    proc = subprocess.Popen([driver, f'--port={port}'], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    base = f'http://127.0.0.1:{port}'
    seen = {}
    ok = False
    session = None
    try:
        for _ in range(100):
            try:
                call(base, 'GET', '/status')
                break
            except OSError:
                time.sleep(0.1)
        args = ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
                '--window-size=1500,1150', f'--user-data-dir={profile}']
        session = call(base, 'POST', '/session', {'capabilities': {'alwaysMatch': {
            'browserName': 'chrome', 'goog:chromeOptions': {'args': args}}}})['sessionId']
        s = f'/session/{session}'
        call(base, 'POST', s + '/url', {'url': a.url})
        deadline = time.monotonic() + a.timeout
        while time.monotonic() < deadline:
            seen = call(base, 'POST', s + '/execute/sync', {'script': PAGE_STATE, 'args': []})
            ok = (seen['frames'] == str(a.frames) and
                  seen['status'] in ('VALID', 'DEGRADED', 'INVALID') and
                  seen['hazard_frame'] != '-' and int(seen['hazard_known_label']) > 0 and
                  seen['hazard_known_pixels'] > 0 and
                  (not a.image or seen['image_lit_pixels'] > 0) and
                  (not a.features or int(seen['features_tracked'] or 0) > 0))
            if ok:
                break
            time.sleep(0.25)
        time.sleep(0.3)  # one more round of the stream: the screenshot shows the settled page
        png = base64.b64decode(call(base, 'GET', s + '/screenshot'))
        with open(a.screenshot, 'wb') as f:
            f.write(png)
    except OSError as e:  # the page or the driver failed: report it, still close the browser
        print(f'page_check: {e}', file=sys.stderr)
        ok = False
    finally:
        # Closing the session closes the browser; a driver stopped first would orphan it.
        if session is not None:
            try:
                call(base, 'DELETE', f'/session/{session}')
            except OSError:
                pass
        proc.terminate()
        proc.wait(timeout=10)
        shutil.rmtree(profile, ignore_errors=True)
    seen['ok'] = ok
    print(json.dumps(seen))
    if not ok:
        print(f'page_check: the page did not show {a.frames} frames, a status and a hazard map '
              f'within {a.timeout} s', file=sys.stderr)
    return 0 if ok else 1


if __name__ == '__main__':
    sys.exit(main())

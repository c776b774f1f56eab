#!/usr/bin/python3
"""Fig. 2b and Fig. 17's orderings, reduced (ctest paper_orderings_test, ~6 s):

  paper_orderings_test.py SWF-EVAL OUT

runs `swf-eval paper OUT --runs 1 --only fig02b,fig17` and fails (exit 1, each failure named)
unless
  Fig. 2b: in every bin of at least 30 landmarks the SWF(5) height error is within 0.75-1.33x the
           CRLB after 25 frames (the estimator attains the bound), below 0.3x the first frame's
           bound (fusing frames over time), and the 25-frame bound falls off the axis (the motion
           baseline effect);
  Fig. 17: VSDF(3) with the Schur term's diagonal elements (eq. 12 read literally) ends above
           SWF(3) in final MSE (the paper: VSDF converges worse)."""
import json
import os
import subprocess
import sys

MIN_LANDMARKS = 30


def main():
    swf_eval, out = sys.argv[1], sys.argv[2]
    subprocess.run([swf_eval, 'paper', out, '--runs', '1', '--only', 'fig02b,fig17'], check=True,
                   stdout=subprocess.DEVNULL)
    failures = []
    with open(os.path.join(out, 'fig02b_focus_of_expansion.json')) as f:
        b = json.load(f)
    crlb = b['crlb_25_frames_m']
    for k, n in enumerate(b['landmarks_per_bin']):
        if n < MIN_LANDMARKS:
            continue
        ratio = b['swf5_rms_m'][k] / crlb[k]
        print('Fig. 2b bin %d (%d landmarks): SWF(5) %.3f m, CRLB %.3f m (%.2fx), first frame '
              '%.3f m' % (k, n, b['swf5_rms_m'][k], crlb[k], ratio, b['crlb_first_frame_m'][k]))
        if not 0.75 <= ratio <= 1.33:
            failures.append('Fig. 2b bin %d: SWF(5) %.2fx the CRLB' % (k, ratio))
        if not b['swf5_rms_m'][k] < 0.3 * b['crlb_first_frame_m'][k]:
            failures.append('Fig. 2b bin %d: SWF(5) not below 0.3x the first frame\'s bound' % k)
    if not all(x > y for x, y in zip(crlb, crlb[1:])):
        failures.append('Fig. 2b: the 25-frame CRLB does not fall off the axis: %s' % crlb)
    with open(os.path.join(out, 'fig17_vsdf.json')) as f:
        v = json.load(f)
    mse = v['final_mse_m2_mean']
    print('Fig. 17: final MSE SWF(3) %.4g, VSDF(3) diagonal %.4g, block %.4g, batch %.4g m^2' %
          (mse['swf3'], mse['vsdf3_diagonal'], mse['vsdf3_block'], mse['batch']))
    if not mse['vsdf3_diagonal'] > mse['swf3']:
        failures.append('Fig. 17: VSDF(3) diagonal %.4g m^2 not above SWF(3) %.4g m^2' %
                        (mse['vsdf3_diagonal'], mse['swf3']))
    for f in failures:
        print('FAIL: ' + f)
    sys.exit(1 if failures else 0)


if __name__ == '__main__':
    main()

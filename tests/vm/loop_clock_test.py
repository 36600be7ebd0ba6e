#!/usr/bin/env python3
"""tests/vm/loop_clock.py on made-up feeder runs, one kept on schedule and one that fell behind
(the whole loop's clock map, docs/testbench.md). Exit status 0 or 1."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CLOCK = os.path.join(HERE, 'loop_clock.py')
ORIGIN = 1767225600000000000  # the dataset's first event, as the simulator writes it
START = 20_000_000_000  # the VM's CLOCK_MONOTONIC when the feeder's clock starts
K = 2.0
FEEDER = f'FEEDER start_mono_ns={START} origin_ns={ORIGIN} slowdown={K:g}'
PERIOD = 33_333_333
W = 400_000  # a frame's write() takes 0.4 ms,
STAMP = 50_000  # and the kernel stamps it 50 us before the write() returns
bad = []


def need(ok, what):
    print(('ok   ' if ok else 'FAIL ') + what)
    if not ok:
        bad.append(what)


def run(d, mode, rows, events_rows, *extra):
    src, dst = os.path.join(d, 'in.tum'), os.path.join(d, 'out.tum')
    with open(src, 'w') as f:
        f.write(''.join(f'{t:.6f} {x} 0 0 0 0 0 1\n' for t, x in rows))
    args = [sys.executable, CLOCK, mode, FEEDER, src, dst, *extra]
    if events_rows is not None:
        ev = os.path.join(d, 'events.csv')
        with open(ev, 'w') as f:
            f.write('kind,t_ns,sent_mono_ns,done_mono_ns\n' +
                    ''.join(f'{k},{t},{v - W},{v}\n' for k, t, v in events_rows))
        args += ['--events', ev]
    p = subprocess.run(args, capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr
    return [(float(l.split()[0]), l.split()[1]) for l in open(dst)], p.stderr


def on_schedule(t_ns):
    return START + K * (t_ns - ORIGIN)


with tempfile.TemporaryDirectory() as d:
    truth = os.path.join(d, 'truth.tum')
    with open(truth, 'w') as f:
        f.write(''.join(f'{(ORIGIN + i * PERIOD) * 1e-9:.6f} 0 0 0 0 0 0 1\n' for i in range(40)))
    frames = [ORIGIN + i * PERIOD for i in range(30)]

    # On schedule: the events (each frame's write() taking 1 ms) and the schedule agree.
    ev = [('f', t, int(on_schedule(t)) + 1_000_000) for t in frames]
    poses = [((v - STAMP) * 1e-9, i) for i, (_, _, v) in enumerate(ev)]
    out, err = run(d, 'to-sim', poses, ev, '--truth', truth)
    need(out is not None and all(abs(t - frames[int(x)] * 1e-9) < 2e-6 for t, x in out) and
         len(out) == 30, f'on schedule, each pose at its frame\'s time ({err.strip()})')
    out, err = run(d, 'to-sim', poses, None, '--truth', truth)
    need(out is not None and all(abs(t - frames[int(x)] * 1e-9) < 1e-3 for t, x in out),
         'on schedule, without the events: the schedule, within 1 ms')

    # Behind: from frame 10 on each frame goes out 0.8 s late, the rest in bursts 1 ms apart.
    late_ev = []
    for i, t in enumerate(frames):
        v = int(on_schedule(t)) if i < 10 else int(on_schedule(frames[10])) + 800_000_000 + (i - 10) * 1_000_000
        late_ev.append(('f', t, v + 500_000))  # the write() returns 0.5 ms later
    poses = [((v - STAMP) * 1e-9, i) for i, (_, _, v) in enumerate(late_ev)]
    out, err = run(d, 'to-sim', poses, late_ev, '--truth', truth)
    need(out is not None and len(out) == 30 and
         all(abs(t - frames[int(x)] * 1e-9) < 2e-6 for t, x in out),
         'behind schedule, on the events: each pose at its frame\'s time')
    out_sched, _ = run(d, 'to-sim', poses, None, '--truth', truth)
    worst = max(abs(t - frames[int(x)] * 1e-9) for t, x in out_sched) if out_sched else 0
    need(worst > 0.3, f'behind schedule, the schedule alone is off by {worst:.2f} s (the old map)')
    out, _ = run(d, 'to-sim', poses[:5], late_ev, '--truth', truth, '--late-s', '0.5')
    need(out is not None and all(abs(t - frames[int(x)] * 1e-9 - 0.5) < 2e-6 for t, x in out),
         '--late-s 0.5 puts each pose half a second late')

    # Labels onto the VM's clock: at a frame's time, when that frame's write() returned (the
    # recording's stamp is within the write), also for a time TUM rounded to the microsecond; between frames, in between.
    labels = [(frames[12] * 1e-9, 12), (frames[20] * 1e-9 + 0.4e-6, 20)]
    out, _ = run(d, 'to-vm', labels, late_ev)
    need(out is not None and abs(out[0][0] - late_ev[12][2] * 1e-9) < 1e-6 and
         abs(out[1][0] - late_ev[20][2] * 1e-9) < 1e-6, 'labels at frames: the frames\' stamps')
    mid = (frames[3] + PERIOD // 2) * 1e-9
    out, _ = run(d, 'to-vm', [(mid, 3)], late_ev)
    want = (late_ev[3][2] + late_ev[4][2] - W) / 2 * 1e-9  # frame 3 returned, frame 4 began
    need(out is not None and abs(out[0][0] - want) < 2e-6, 'a label between frames: in between')

    # A file that is not an events file, or out of order, is refused with one line.
    out, err = run(d, 'to-sim', poses, [('x', 1, 2)], '--truth', truth)
    need(out is None and 'not an event line' in err, 'a malformed events file is refused')
    out, err = run(d, 'to-sim', poses, late_ev[::-1], '--truth', truth)
    need(out is None and 'out of order' in err, 'events out of order are refused')

sys.exit(1 if bad else 0)

#!/usr/bin/env python3
"""The trials of toolchain/sci-gesture-commands.sh (docs/sci.md "Gesture commands at drawn poses").

  sci_gesture_trial.py scenario N   the scene of trial N (YAML on stdout)
  sci_gesture_trial.py kind N       confirm | deny | cross
  sci_gesture_trial.py score DIR K N  score DIR/trial_K..N.jsonl, one line each and a summary

Every draw comes from random.Random(N): the same trial is the same scene on every run.
Targets are placed in displayed pixels with the scene's default camera (640x480,
drivers/scene/src/camera.cpp) and turned into millimetres at the drawn depth.
"""
import json
import math
import os
import random
import sys

FPS = 25
W, H = 640, 480
# The scene's default camera (drivers/scene/include/endotower/scene/camera.hpp).
FX = 0.868 * H
FY = FX * 65.83 / 66.67
CX = (W - 1) / 2 + 0.0125 * H
CY = (H - 1) / 2 - 0.0083 * H
K = [-0.32 / H**2, 0.06 / H**4]
# The ring's items (app/sci/src/sci_menu.cpp): centre angle on screen (y down).
ITEMS = {"CT": -90, "X-RAY": 0, "MRI": 90, "EXIT": 180}
RING_R = 0.355 * H  # inside the 0.30-0.40 H band; an open jaw's tip reads ~10 px nearer
START_FRAMES, MOVE_FRAMES, HOLD_FRAMES = 10, 12, 35
LOOP_FROM = START_FRAMES + MOVE_FRAMES + HOLD_FRAMES  # the loop or stroke begins


def kind(n):
    return ("confirm", "deny", "cross")[(n - 1) % 3]


def to_mm(xd, yd, z):
    """Displayed pixel -> camera-frame point at depth z (inverse of the scene's projection)."""
    dx, dy = xd - CX, yd - CY
    rd = math.hypot(dx, dy)
    r = rd
    for _ in range(50):  # Newton on r f(r^2) = rd
        f = 1 + K[0] * r * r + K[1] * r**4
        s = 1 + 3 * K[0] * r * r + 5 * K[1] * r**4
        r -= (r * f - rd) / s
    xu, yu = (CX + dx * r / rd, CY + dy * r / rd) if rd > 0 else (xd, yd)
    return [round((xu - CX) / FX * z, 3), round((yu - CY) / FY * z, 3), round(z, 3)]


def fmt(v):
    return "[" + ", ".join("%g" % x for x in v) + "]"


def scenario(n):
    rnd = random.Random(n)
    k = kind(n)
    light = round(rnd.uniform(0.5, 1.0), 2)
    seed = rnd.randrange(1, 10000)
    head = "name: sci_gesture_%d\ndescription: %s trial %d\nseed: %d\nlight: %g\n" % (n, k, n, seed, light)
    if k == "cross":
        z = rnd.uniform(62, 80)
        cx, cy = rnd.uniform(-4, 4), rnd.uniform(-4, 4)
        side = rnd.choice([-1, 1])  # both tools from the top or both from the bottom
        d2 = rnd.choice([5, 10])
        a, b = [cx - 5.15, cy, z], [cx + 5.19, cy, z + 3]
        a0, b0 = [cx + 8, cy + 6 * side, z], [cx - 8, cy + 6 * side, z + 3]
        ap, bp = [cx + 4, cy + 4 * side, z], [cx - 4, cy + 4 * side, z + 3]

        def motion(p, pp):
            return ("[{dwell: 10}, {move: %s, frames: 15}, {dwell: 40}, {move: %s, frames: 10}, "
                    "{dwell: 10}, {move: %s, frames: 10}, {dwell: 55}]" % (fmt(p), fmt(pp), fmt(p)))

        return head + (
            "frames: 150\ntools:\n"
            "  - {diameter_mm: 5, tip: scissors, jaw: closed, pivot_mm: [90, %d, 20], start: {tip_mm: %s},\n"
            "     motion: %s}\n"
            "  - {diameter_mm: %d, tip: grasper, jaw: closed, pivot_mm: [-90, %d, 25], start: {tip_mm: %s},\n"
            "     motion: %s}\n" % (60 * side, fmt(a0), motion(a, ap), d2, 60 * side, fmt(b0),
                                    motion(b, bp))), "-"
    item = rnd.choice(sorted(ITEMS))
    z = rnd.uniform(55, 85)
    d = rnd.choice([5, 10])
    th = math.radians(ITEMS[item])
    # Where the tool comes in from: across the view from the item (within 70 degrees of
    # straight across), so its shaft is in the picture.
    phi = th + math.pi + math.radians(rnd.uniform(-70, 70))
    target = to_mm(W / 2 + RING_R * math.cos(th), H / 2 + RING_R * math.sin(th), z)
    start = to_mm(W / 2 + 0.06 * H * math.cos(phi), H / 2 + 0.06 * H * math.sin(phi), z)
    pivot = [round(110 * math.cos(phi), 1), round(110 * math.sin(phi), 1), 15]
    if k == "confirm":
        # One turn through 12 points of a circle (radius 3-5 mm, 0.9-1.4 s) whose centre
        # lies in a drawn direction from the tip, either way round.
        radius, frames = rnd.uniform(3, 5), rnd.randrange(23, 36)
        psi, sense = rnd.uniform(0, 2 * math.pi), rnd.choice([-1, 1])
        centre = [target[0] + radius * math.cos(psi), target[1] + radius * math.sin(psi)]
        steps = []
        for j in range(1, 13):
            a = psi + math.pi + sense * 2 * math.pi * j / 12
            point = [round(centre[0] + radius * math.cos(a), 3), round(centre[1] + radius * math.sin(a), 3), target[2]]
            steps.append("{move: %s, frames: %d}" % (fmt(point), frames * j // 12 - frames * (j - 1) // 12))
        then = ", ".join(steps)
    else:  # a straight stroke across the item and back
        side = [round(target[0] - 8 * math.sin(th), 3), round(target[1] + 8 * math.cos(th), 3), target[2]]
        then = "{move: %s, frames: 15}, {move: %s, frames: 15}" % (fmt(side), fmt(target))
    return head + (
        "frames: 135\ntools:\n"
        "  - {diameter_mm: %d, tip: grasper, jaw: closed, pivot_mm: %s, start: {tip_mm: %s},\n"
        "     motion: [{dwell: %d}, {move: %s, frames: %d}, {dwell: %d, jaw: open}, %s, {dwell: 40}]}\n"
        "# item: %s\n" % (d, fmt(pivot), fmt(start), START_FRAMES, fmt(target), MOVE_FRAMES, HOLD_FRAMES,
                          then, item)), item


def score(folder, first, last):
    ok = {"confirm": [0, 0], "deny": [0, 0], "cross": [0, 0]}
    times = {"confirm": [], "cross": []}
    for n in range(first, last + 1):
        k = kind(n)
        path = "%s/trial_%d.jsonl" % (folder, n)
        if not os.path.exists(path):  # not run (KIND= runs one kind)
            continue
        item = scenario(n)[1]
        lines = [json.loads(l) for l in open(path)]
        ev = [(l["frame"], l["sci"]["event"], l["sci"]["highlighted"]) for l in lines if l["sci"]["event"]]
        names = [e[1] for e in ev if e[1] not in ("highlight", "unhighlight")]
        flicker = sum(e[1] == "unhighlight" for e in ev)
        note = "%d unhighlight%s; " % (flicker, "" if flicker == 1 else "s") if flicker else ""
        if k == "cross":
            good = names == ["quadrant", "deactivate"]
            if good:
                t = (ev[names.index("quadrant")][0] - 25) / FPS  # the tools rest from frame 25
                times["cross"].append(t)
                note += "quadrant %.2f s after the tools came to rest" % t
        else:
            # What counts is what was executed: the select of the intended item, then its
            # action by the loop (confirm) or none (deny); a highlight that flickers at the
            # item's edge is no command. Anything after the command is left to the scene.
            done = "exit" if item == "EXIT" else "confirm"
            want = ["activate_button", "select", done if k == "confirm" else "deny"]
            sel = [e for e in ev if e[1] == "select"]
            good = names[:3] == want and sel[0][2] == item
            # A confirm before the loop began is the tip's jitter read as a loop.
            at = ev[[e[1] for e in ev].index(names[2])][0] if good else 0
            if good and k == "confirm" and at < LOOP_FROM:
                good = False
                note += "confirmed on frame %d, before the loop began" % at
            elif good and k == "confirm":
                t = (at - START_FRAMES) / FPS
                times["confirm"].append(t)
                note += "selected in %.2f s" % t
            elif good:
                deny = [e for e in ev if e[1] == "deny"][0]
                good = deny[0] - sel[0][0] == 2 * FPS  # denied 2.0 s after the select
        ok[k][0] += good
        ok[k][1] += 1
        print("trial %3d %-7s %-6s %-4s %s  %s" % (n, k, item, "ok" if good else "FAIL",
              " ".join("%d:%s%s" % (f, e, "(" + h + ")" if h and e == "highlight" else "") for f, e, h in ev),
              note))
    for k, (a, b) in ok.items():
        if b:
            print("%-7s %d/%d = %.1f %%" % (k, a, b, 100.0 * a / b))
    for k, ts in times.items():
        if ts:
            ts.sort()
            print("%s time: median %.2f s, range %.2f-%.2f s" % (k, ts[len(ts) // 2], ts[0], ts[-1]))
    return 0


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    cmd = sys.argv[1]
    if cmd == "scenario":
        sys.stdout.write(scenario(int(sys.argv[2]))[0])
    elif cmd == "kind":
        print(kind(int(sys.argv[2])))
    elif cmd == "score" and len(sys.argv) == 5:
        sys.exit(score(sys.argv[2], int(sys.argv[3]), int(sys.argv[4])))
    else:
        sys.exit(__doc__)

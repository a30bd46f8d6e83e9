#!/usr/bin/env python3
"""Writes config/quarter_car_diagnosis_demand.csv: the road-actuator demand of
the quarter car's `diagnosis` case (rigctl make-run, diagnosis tests).

Each part is there to make one family of effects visible (docs/diagnosis.md 6):
  * lead-in from home to mid-stroke (0.08 m), slow: start without a jump;
  * steps of several sizes both ways: the hydraulics and the PI loop in full
    (valve saturation, pressure transients: entrained air, leakage);
  * fast drops: the plate leaves the tyre (tyre lift-off);
  * a slow triangle and small steps: low-velocity reversals of rod and body
    (seal and bearing friction, the valve dead band near null);
  * a 1-6 Hz chirp: broadband content for delays and the damper's rebound vs
    compression strokes.
Edges are raised-cosine blends of 30 ms, so the demand needs no filter.
"""
import math
import os

DT = 0.0025
MID = 0.08


def blend(a, b, t, width=0.03):
    if t <= 0:
        return a
    if t >= width:
        return b
    return a + (b - a) * 0.5 * (1 - math.cos(math.pi * t / width))


segments = []  # (duration, function of local time -> demand)


def hold(value, duration):
    segments.append((duration, lambda t, v=value: v))


def step(a, b, duration):
    segments.append((duration, lambda t, a=a, b=b: blend(a, b, t)))


def ramp(a, b, duration):
    segments.append((duration, lambda t, a=a, b=b, d=duration: a + (b - a) * min(1.0, t / d)))


def chirp(center, amplitude, f0, f1, duration):
    def f(t, c=center, A=amplitude, f0=f0, f1=f1, d=duration):
        k = (f1 - f0) / d
        taper = min(1.0, t / 0.3, (d - t) / 0.3)
        return c + A * taper * math.sin(2 * math.pi * (f0 * t + 0.5 * k * t * t))
    segments.append((duration, f))


hold(0.0, 0.5)
ramp(0.0, MID, 1.5)
hold(MID, 0.5)
step(MID, MID + 0.030, 0.9)
step(MID + 0.030, MID - 0.020, 0.9)
step(MID - 0.020, MID + 0.045, 0.9)
step(MID + 0.045, MID - 0.010, 0.9)   # fast 55 mm drop: lift-off
step(MID - 0.010, MID + 0.003, 0.6)   # small steps about the middle
step(MID + 0.003, MID - 0.003, 0.6)
step(MID - 0.003, MID, 0.6)
ramp(MID, MID + 0.02, 1.0)            # slow triangle: 20 mm/s reversals
ramp(MID + 0.02, MID - 0.02, 2.0)
ramp(MID - 0.02, MID, 1.0)
chirp(MID, 0.008, 1.0, 6.0, 3.0)
step(MID, MID + 0.040, 0.8)
step(MID + 0.040, MID - 0.030, 1.0)   # 70 mm drop
step(MID - 0.030, MID, 0.8)



def write(name, segs, what):
    out = os.path.join(os.path.dirname(__file__), "..", "..", "..", "config", name)
    with open(out, "w") as f:
        f.write(f"# {what}; made by tools/scripts/excitation/quarter_car_diagnosis.py\n")
        f.write("t,x_ref\n")
        k = 0
        for duration, fn in segs:
            n = int(round(duration / DT))
            for i in range(n):
                f.write(f"{k * DT:.4f},{fn(i * DT):.7f}\n")
                k += 1
    print(f"{out}: {k} samples, {k * DT:.2f} s")


write("quarter_car_diagnosis_demand.csv", segments, "Demand of the quarter car's diagnosis runs")

# The lift-off variant: the same table with a burst at the wheel-hop
# frequency (sqrt(kt / Mw) / 2 pi = 24 Hz) in the middle, +-20 mm. The closed loop
# cannot follow it, but the rod moves at the valve's full flow and the wheel
# resonates: the tyre load swings by more than the static 2.7 kN, so a tyre
# that cannot pull leaves the plate. Nothing in the clean table does that
# (the lowest tyre load there is about 0.3 kN).
def wheel_hop_burst():
    return (1.2, lambda t: MID + 0.020 * min(1.0, t / 0.1, (1.2 - t) / 0.1) * math.sin(2 * math.pi * 24.0 * t))


# Two bursts: one in the part the diagnosis fits, one in the last 20 % it holds out.
segments_liftoff = segments[:11] + [wheel_hop_burst()] + segments[11:15] + [wheel_hop_burst()] + segments[15:]
write("quarter_car_liftoff_demand.csv", segments_liftoff, "Demand of the quarter car's lift-off runs (a wheel-hop burst added)")

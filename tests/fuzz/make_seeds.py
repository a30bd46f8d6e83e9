#!/usr/bin/env python3
"""Writes the seed corpora of tests/fuzz/corpus/ (run once; the output is
committed). Config seeds are the shipped config/*.yaml plus small variants;
the binary harnesses' seeds follow the input layouts documented at the top of
fuzz_canopen.cpp and fuzz_modbus.cpp. Standard library only:
    python3 tests/fuzz/make_seeds.py
"""
import os
import re
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
CORPUS = os.path.join(HERE, "corpus")


def write(target, name, data):
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- config
def config_seeds():
    texts = {}
    for name in sorted(os.listdir(os.path.join(ROOT, "config"))):
        if name.endswith(".yaml"):
            with open(os.path.join(ROOT, "config", name)) as f:
                texts[name] = f.read()
    for name, text in texts.items():
        write("config", name, text)
    qc = texts["quarter_car.yaml"]
    # The hardware drivers: the modbus and canopen sections become required.
    write("config", "quarter_car-modbus_canopen.yaml", qc.replace("driver: sim", "driver: modbus_canopen", 1))
    # A table calibration, a 32-bit float input and an RTU transport.
    v = qc.replace("calibration: {gain: 6.103515625e-6, offset: 0.0}}    # +-0.2 m LVDT",
                   "calibration: {table: {raw: [-32768, 0, 32767], si: [-0.2, 0.0, 0.2]}}}", 1)
    v = v.replace("address: 7, format: int16", "address: 8, format: float32, order: cdab", 1)
    write("config", "quarter_car-table.yaml", v)
    write("config", "quarter_car-rtu.yaml",
          qc.replace("transport: tcp", "transport: rtu\n  device: /dev/ttyUSB0\n  baud: 115200\n"
                     "  parity: N\n  data_bits: 8\n  stop_bits: 1", 1).replace("response_timeout_s: 0.002 ", "response_timeout_s: 0.004 ", 1).replace("  host: 127.0.0.1\n", "", 1)
          .replace("  port: 1502\n", "", 1))
    write("config", "quarter_car-sine.yaml", re.sub(r"profile:\n(  .*\n)+",
          "profile:\n  type: sine\n  filter_tau_s: 0.0\n  start: measured\n  hold_s: 1.0\n  ramp_target: 0.0\n"
          "  ramp_rate: 0.01\n  amplitude: 0.01\n  frequency_hz: 1.0\n  cycles: 3\n", qc, count=1))
    # Near-valid: small broken files the loader must reject with ConfigError.
    write("config", "empty.yaml", "")
    write("config", "scalar.yaml", "42\n")
    write("config", "list.yaml", "- rig: quarter_car\n")
    write("config", "unknown_rig.yaml", "rig: wind_tunnel\ndriver: sim\nseed: 1\n")
    write("config", "bad_syntax.yaml", "rig: [quarter_car\n")
    write("config", "cases_not_map.yaml", "rig: quarter_car\ncases: [a, b]\n")
    write("config", "complex_key.yaml", "? [a, b]\n: 1\nrig: quarter_car\n")
    # Regressions: a list as a mapping key escaped as yaml-cpp's BadConversion
    # instead of a ConfigError (fixed in config/config_reader.cpp, key_text).
    write("config", "regression-complex_key_root.yaml", qc + "? [a, b]\n: 1\n")
    write("config", "regression-complex_key_sensors.yaml",
          qc.replace("sensors:\n", "sensors:\n  ? {x: 1}\n  : {noise_sd: 0, bits: 16, range: [0, 1], offset: 0}\n", 1))
    write("config", "regression-complex_key_case.yaml", qc + "cases:\n  ? [c]\n  : {seed: 2}\n")
    # Regression: config_case_names() of a file without `cases:` threw
    # YAML::InvalidNode (the harness passes sizes divisible by 8 through it).
    write("config", "regression-no_cases.yaml", "rig: qc\n")
    write("config", "anchors.yaml", "base: &b {period_s: 0.0025}\nloop: *b\nrig: quarter_car\n")


# ---------------------------------------------------------------- run files
def run_file_seeds():
    # First byte: bits 0-2 rig (0 all columns, 1 quarter_car, 2 pneumatic_rotary,
    # 3 half_car, 4 linear_axis, 5 damper, 7 unknown), bit 3 drop_bad_rows,
    # bits 4-7 min_rows.
    def rows(header, n, f, dt=0.0025, jitter=None):
        out = [",".join(header)]
        for i in range(n):
            t = i * dt + (jitter(i) if jitter else 0.0)
            out.append(",".join(["%g" % t] + [("%g" % f(i, k)) for k in range(len(header) - 1)]))
        return "\n".join(out) + "\n"

    qc = ["t", "x_ref", "u", "x_r", "x_w", "x_b", "v_w", "p1"]
    write("run_file", "quarter_car.csv",
          bytes([0x31]) + ("# rig: quarter_car\n# sample_rate_hz: 400\n# seed: 1\n" +
                           rows(qc, 12, lambda i, k: 0.001 * i * (k + 1))).encode())
    write("run_file", "quarter_car_jitter.csv",
          bytes([0x31]) + rows(qc, 12, lambda i, k: 0.5 * k - i, jitter=lambda i: 0.0001 * (i % 3)).encode())
    write("run_file", "pneumatic_crlf.csv",
          bytes([0x22]) + rows(["t", "theta_d", "u", "theta", "dp", "omega", "extra"], 4,
                               lambda i, k: i + k).replace("\n", "\r\n").encode())
    write("run_file", "half_car_bom.csv",
          bytes([0x23]) + b"\xef\xbb\xbf" + rows(["t", "z_r1", "z_r2", "z_s", "phi", "z_u1", "z_u2"], 3,
                                                  lambda i, k: 0.01 * k).encode())
    write("run_file", "damper_bad_rows.csv",
          bytes([0x2D]) + b"# rig: damper\nt,x,f,v\n0,1,2,3\n0.001,1,nan,3\n0.002,1,2\n0.003,x,2,3\n"
                          b"0.004,1,2,3,4\n0.005,1,2,3\n0.006,,2,3\n0.007,1e999,2,3\n0.008,1,2,3\n")
    write("run_file", "linear_axis_gap.csv",
          bytes([0x24]) + b"t,u,x\n0,0,0\n0.001,0,0\n0.002,0,0\n0.010,0,0\n0.011,0,0\n")
    write("run_file", "all_columns.csv",
          bytes([0x20]) + b"# sample_rate_hz: abc\nt,a,b\n0,1,2\n1,1,2\n2,1,2\n1.5,1,2\n")
    write("run_file", "header_only.csv", bytes([0x00]) + b"# only: metadata\n\nt, a ,a\n")
    # Regressions: finite times spanning more than a double holds gave an
    # infinite resampling grid (UB casting inf to size_t, then a huge
    # allocation) or dt = inf (fixed in tools/runfile/run_file.cpp).
    write("run_file", "regression-huge_span_jitter.csv",
          bytes([0x00]) + b"t,a\n-1.6e308,0\n-0.6e308,0\n0.5e308,0\n1.5e308,0\n")
    write("run_file", "regression-infinite_step.csv", bytes([0x00]) + b"t,a\n-1.7e308,0\n1.7e308,0\n")
    with open(os.path.join(ROOT, "tests", "data", "mr_damper_random_50.csv"), "rb") as f:
        head = b"".join(f.readlines()[:40])
    write("run_file", "mr_damper_head.csv", bytes([0xA5]) + head)


# ---------------------------------------------------------------- Modbus
def modbus_seeds():
    def point(unit, fmt, order, holding, address, table=0, extra_flags=0):
        flags = fmt | (order << 3) | (0x20 if holding else 0) | extra_flags
        return struct.pack("<BBHBB", unit, flags, address, table, 0)

    def linear(gain, offset):
        return struct.pack("<dd", gain, offset)

    def regs(*values):
        return struct.pack("<%dH" % len(values), *values)

    # The shipped quarter-car DAQ: 8 inputs, int16/uint16, one block of 8.
    pts = [point(1, 0 if k not in (5, 6) else 1, 0, False, k) for k in range(8)]
    cal = b"".join(linear(6.103515625e-6, 0.0) for _ in range(8))
    write("modbus", "quarter_car_inputs",
          struct.pack("<bBB", 4, 125, 8) + b"".join(pts) + cal + regs(0x1234, 0xFFFF) +
          regs(100, 0xFF9C, 0, 32767, 0x8000, 65535, 12000, 0xF000))
    # Every format and word order, two units, both tables, gaps, a table calibration.
    pts = [point(1, 4, 0, False, 0), point(1, 4, 1, False, 2), point(1, 2, 2, False, 10),
           point(1, 3, 3, False, 12), point(2, 0, 2, True, 100), point(2, 1, 3, True, 101, table=(3 << 1) | 1)]
    cal = (linear(1.0, 0.0) * 5 + struct.pack("<6d", -32768, -0.2, 0, 0.0, 32767, 0.2))
    reply = regs(0x3F80, 0x0000, 0x0000, 0x3F80, 0xFFFF, 0xFFFF, 0, 0, 0, 0, 0x0100, 0x0000, 0x0000, 0x0001,
                 0x7FC0, 0x0000, 0x1234, 0x5678)
    write("modbus", "mixed_formats", struct.pack("<bBB", 4, 125, 6) + b"".join(pts) + cal + regs(0x7F80, 0) + reply)
    # A float32 NaN and infinity, a decreasing table, max_registers 2 (one block per point).
    pts = [point(1, 4, 0, False, 0, table=(2 << 1) | 1), point(1, 4, 0, False, 2)]
    cal = struct.pack("<4d", 0.0, 10.0, 1.0, -10.0) + linear(-2.0, 5.0)
    write("modbus", "float_nan_inf", struct.pack("<bBB", 0, 2, 2) + b"".join(pts) + cal + regs(0x7FC0, 1) +
          regs(0x7F80, 0x0000, 0xFF80, 0x0000))
    # Bad plans: max_gap < 0, a point past 65535, unit id 300.
    write("modbus", "bad_options", struct.pack("<bBB", -1, 1, 1) + point(1, 0, 0, False, 0) + linear(1, 0))
    write("modbus", "bad_point", struct.pack("<bBB", 0, 125, 2) + point(1, 2, 0, False, 65535) +
          point(44, 0, 0, False, 5, extra_flags=0x40) + linear(1, 0) * 2)


# ---------------------------------------------------------------- CAN
def canopen_seeds():
    def setup(node=1, entries=3, types=0b000101, types2=0, sdo=1001, hb_consumer=501, hb_period=201):
        return struct.pack("<BBBBHHH", node, entries, types, types2, sdo, hb_consumer, hb_period)

    def frame(can_id, data, action=1, length=None):
        data = bytes(data)
        return struct.pack("<IB", can_id, len(data) if length is None else length) + data.ljust(8, b"\0") + \
            bytes([action])

    # types: entry i type = bits 2i..2i+1 (0 8-bit, 1 16-bit, 2 32-bit); signed when bit i of types^types2.
    node = 1
    # A valve start-up and operation: boot-up, SDO download/upload answers, heartbeats, TPDO, EMCY.
    valve = (setup(node, 3, 0b010101, 0b000110) +
             frame(0x700 + node, [0x00]) +
             frame(0x580 + node, [0x60, 0x42, 0x60, 0x00, 0, 0, 0, 0], action=0x11) +
             frame(0x580 + node, [0x4B, 0x11, 0x63, 0x01, 0x00, 0x40, 0, 0], action=0x31) +
             frame(0x700 + node, [0x05]) +
             frame(0x180 + node, [0x0F, 0x00, 0x00, 0x20, 0x10, 0x00]) +
             frame(0x080 + node, [0x30, 0x81, 0x11, 1, 2, 3, 4, 5]) +
             frame(0x080 + node, [0, 0, 0, 0, 0, 0, 0, 0]) +
             frame(0x700 + node, [0x7F], action=0x0F))
    write("canopen", "valve_session", valve)
    # Requests to the simulated valve's SDO server and NMT commands.
    server = (setup(node) +
              frame(0x600 + node, [0x40, 0x41, 0x60, 0x00, 0, 0, 0, 0]) +
              frame(0x600 + node, [0x2B, 0x40, 0x60, 0x00, 0x0F, 0, 0, 0]) +
              frame(0x600 + node, [0x2F, 0x41, 0x60, 0x00, 0x01, 0, 0, 0]) +
              frame(0x600 + node, [0x23, 0x00, 0x20, 0x00, 1, 2, 3, 4]) +
              frame(0x600 + node, [0x40, 0x00, 0x20, 0x00, 0, 0, 0, 0]) +
              frame(0x600 + node, [0x40, 0x01, 0x20, 0x00, 0, 0, 0, 0]) +
              frame(0x600 + node, [0x60, 0x42, 0x60, 0x05, 0, 0, 0, 0]) +
              frame(0x600 + node, [0x80, 0x42, 0x60, 0x00, 0, 0, 4, 5]) +
              frame(0x000, [0x01, node]) + frame(0x000, [0x82, 0]) + frame(0x000, [0x03, 0]))
    write("canopen", "sdo_server_nmt", server)
    # Malformed: RTR, EFF, error frames, len > 8, wrong lengths, SYNC, TIME, unknown COB-IDs, aborts.
    bad = (setup(5, 9, 0xAA, 0xAA, sdo=0, hb_consumer=0, hb_period=0) +
           frame(0x40000185, [1, 2]) + frame(0x80000185, [1, 2]) + frame(0x20000000, [0] * 8) +
           frame(0x185, [1] * 8, length=15) + frame(0x705, [0x05, 0]) + frame(0x085, [1, 2, 3]) +
           frame(0x080, []) + frame(0x080, [7]) + frame(0x100, [0] * 6) + frame(0x680, [0] * 8) +
           frame(0x7E5, [0]) + frame(0x800, [0]) + frame(0x585, [0x80, 0, 0x10, 0, 0, 0, 4, 5], action=0x11) +
           frame(0x585, [0x41, 0, 0x10, 0, 0, 0, 0, 0], action=0x31) +
           frame(0x585, [0x43, 0x01, 0x10, 0, 1, 2, 3, 4], action=0x31) +
           frame(0x585, [0x60, 0, 0, 0, 0, 0, 0, 0], length=4, action=0x11) +
           frame(0x705, [0x85]) + frame(0x705, [0x00], action=0x0F) + frame(0x705, [0x33]))
    write("canopen", "malformed", bad)
    # A node id of 0 and 200, and an SDO timeout.
    write("canopen", "odd_nodes", setup(0, 1) + frame(0x700, [0]) + frame(0x580, [0x60] + [0] * 7, action=0x11))
    write("canopen", "timeout", setup(200, 2, 0, 0, sdo=2) + frame(0x7C8, [5], action=0x1F) + frame(0x648, [0], action=0x0F))


# ---------------------------------------------------------------- dictionaries
def dictionaries():
    keys = set()
    for name in sorted(os.listdir(os.path.join(ROOT, "config"))):
        if name.endswith(".cpp"):
            with open(os.path.join(ROOT, "config", name)) as f:
                keys.update(re.findall(r'\.(?:number|integer|boolean|text|choice|numbers|child|has)\("([A-Za-z0-9_]+)"',
                                       f.read()))
    words = ['"%s:"' % k for k in sorted(keys)]
    words += ['"%s"' % w for w in ["cases:", "rig: ", "quarter_car", "half_car", "pneumatic_rotary", "sim",
                                   "modbus", "modbus_canopen", "true", "false", ".nan", ".inf", "-.inf", "~",
                                   "1e308", "-1e-320", "0x7fffffffffffffff", "&a ", "*a", "<<: ", "? ", "- ",
                                   "[", "]", "{", "}", ": ", "\\x0a  ", "!!str ", "!!map", "---", "...", "'", "|"]]
    with open(os.path.join(HERE, "config.dict"), "w") as f:
        f.write("# libFuzzer dictionary: config keys read by config/*.cpp (make_seeds.py) and YAML syntax.\n")
        f.write("\n".join(words) + "\n")
    with open(os.path.join(HERE, "run_file.dict"), "w") as f:
        f.write("# libFuzzer dictionary: run-file syntax and numbers the reader must handle.\n")
        f.write("\n".join('"%s"' % w for w in [
            "# ", ": ", "t,", ",", "\\x0d\\x0a", "\\x0a", "\\xef\\xbb\\xbf", "nan", "inf", "-inf", "1e308", "1e-320",
            "1e999", "0x1p-1074", "x_ref", "x_r", "x_w", "x_b", "theta", "dp", "z_s", "phi", "u", "x", "f",
            "sample_rate_hz", "0.0025", "0.00251", "-0"]) + "\n")


dictionaries()
config_seeds()
run_file_seeds()
modbus_seeds()
canopen_seeds()

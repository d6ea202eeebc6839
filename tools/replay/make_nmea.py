#!/usr/bin/python3
"""Writes the pose_nmea driver's process replay input (run once; the file is then kept in the
repository, as a receiver's recording would be):

  tools/replay/make_nmea.py tests/replay/pose_nmea.input.nmea

A GNSS/INS receiver's NMEA 0183 stream at 5 Hz, 6 s of a car in West Oakland accelerating from
rest and turning right (GGA, RMC, HDT, VTG per epoch, as an RTK-fixed receiver sends them), with
what a real stream carries besides: a GSV sentence (not used, counted), one line with a bad
checksum, a line of noise, an epoch where the fix degrades to single-point and one with no fix
(quality 0: not published), a talker the config does not accept, and an epoch without HDT (its
heading from the course over ground). Deterministic: no random numbers.
"""
import math
import sys


def nmea(body):
    c = 0
    for ch in body.encode():
        c ^= ch
    return "$%s*%02X\r\n" % (body, c)


def dm(value, lat):
    """Degrees as NMEA's ddmm.mmmmmm / dddmm.mmmmmm and the hemisphere letter."""
    hemi = ("N" if value >= 0 else "S") if lat else ("E" if value >= 0 else "W")
    v = abs(value)
    d = int(v)
    m = (v - d) * 60.0
    return ("%02d%09.6f" if lat else "%03d%09.6f") % (d, m), hemi


def main():
    if len(sys.argv) != 2:
        raise SystemExit(__doc__)
    lat0, lon0 = 37.8064, -122.2899   # West Oakland
    lat, lon = lat0, lon0
    heading = 90.0                    # degrees from north, clockwise
    speed = 0.0                       # m/s
    lines = []
    t0 = 17 * 3600 + 30 * 60          # 17:30:00 UTC
    for k in range(31):
        t = t0 + 0.2 * k
        hh, rem = divmod(t, 3600)
        mm, ss = divmod(rem, 60)
        stamp = "%02d%02d%05.2f" % (hh, mm, ss)
        la, ns = dm(lat, True)
        lo, ew = dm(lon, False)
        quality, sats, hdop = 4, 16, 0.6
        if k == 12:
            quality, sats, hdop = 1, 7, 1.9    # the fix degrades under a bridge ...
        if k == 13:
            quality, sats, hdop = 0, 3, 9.9    # ... and is lost for one epoch
        knots = speed / 0.514444
        if k == 5:
            lines.append(nmea("GPGSV,3,1,12,01,40,083,46,02,17,308,41,12,07,344,39,14,22,228,45"))
        if k == 9:
            body = "GNGGA,%s,%s,%s,%s,%s,4,16,0.6,12.0,M,-32.1,M,1.0,0000" % (stamp, la, ns, lo, ew)
            lines.append("$" + body + "*00\r\n")   # a corrupted checksum: rejected
            lines.append("\x00\x7f#noise on the line\r\n")
        if k == 20:
            lines.append(nmea("PQGGA,%s,%s,%s,%s,%s,4,16,0.6,12.0,M,-32.1,M,1.0,0000" % (stamp, la, ns, lo, ew)))
        lines.append(nmea("GNGGA,%s,%s,%s,%s,%s,%d,%02d,%.1f,12.0,M,-32.1,M,%s,0000" %
                          (stamp, la, ns, lo, ew, quality, sats, hdop, "1.0" if quality == 4 else "")))
        lines.append(nmea("GNRMC,%s,%s,%s,%s,%s,%s,%.3f,%.2f,041226,,,%s" %
                          (stamp, "A" if quality else "V", la, ns, lo, ew, knots, heading, "R" if quality == 4 else "A")))
        if k != 25:
            lines.append(nmea("GNHDT,%.2f,T" % heading))
        lines.append(nmea("GNVTG,%.2f,T,,M,%.3f,N,%.3f,K,D" % (heading, knots, speed * 3.6)))
        # The next epoch: accelerate at 2 m/s^2 to 8 m/s, turn right at 12 deg/s after 2 s.
        dt = 0.2
        speed = min(8.0, speed + 2.0 * dt)
        if k >= 10:
            heading = (heading + 12.0 * dt) % 360.0
        r = 6378137.0
        lat += math.degrees(speed * dt * math.cos(math.radians(heading)) / r)
        lon += math.degrees(speed * dt * math.sin(math.radians(heading)) / (r * math.cos(math.radians(lat))))
    with open(sys.argv[1], "w", newline="") as f:
        f.write("".join(lines))


if __name__ == "__main__":
    main()

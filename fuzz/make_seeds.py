#!/usr/bin/env python3
"""Writes the seed corpora fuzz/corpus/<harness>/ from the real files in data/ and config/
(small slices where the file is big, so each seed runs in milliseconds). The LCM seeds come from
build-fuzz/fuzz_lcm_seeds (fuzz/lcm_seeds.cc). Run from the repository root:
    python3 fuzz/make_seeds.py            (needs osmium-tool for the PBF slices)
"""
import os, shutil, struct, subprocess, sys, tempfile
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def out(harness, name, data):
    d = os.path.join(CORPUS, harness)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def osm_slice(src, pick_ways, max_ways, with_relations):
    """The first max_ways ways pick_ways() accepts (and, with_relations, the first relations whose
    way members are all among them), with exactly the nodes they use."""
    tree = ET.parse(src)
    root = tree.getroot()
    ways = [w for w in root.findall("way") if pick_ways(w)]
    rels = []
    if with_relations:
        by_id = {w.get("id"): w for w in root.findall("way")}
        for r in root.findall("relation"):
            members = [m.get("ref") for m in r.findall("member") if m.get("type") == "way"]
            if members and all(m in by_id for m in members):
                rels.append(r)
            if len(rels) >= max_ways:
                break
        keep = set()
        for r in rels:
            keep.update(m.get("ref") for m in r.findall("member") if m.get("type") == "way")
        ways = [by_id[i] for i in sorted(keep, key=int)]
    else:
        ways = ways[:max_ways]
    node_ids = set()
    for w in ways:
        node_ids.update(nd.get("ref") for nd in w.findall("nd"))
    for r in rels:
        node_ids.update(m.get("ref") for m in r.findall("member") if m.get("type") == "node")
    new = ET.Element("osm", root.attrib)
    b = root.find("bounds")
    if b is not None:
        new.append(b)
    for n in root.findall("node"):
        if n.get("id") in node_ids:
            new.append(n)
    for w in ways:
        new.append(w)
    for r in rels:
        new.append(r)
    ET.indent(new)
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(new)


def highway(w):
    return any(t.get("k") == "highway" for t in w.findall("tag"))


def pcap_records(path, n):
    with open(path, "rb") as f:
        data = f.read()
    pos, recs = 24, []
    order = "<" if data[:4] in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1") else ">"
    while pos + 16 <= len(data) and len(recs) < n:
        incl = struct.unpack(order + "I", data[pos + 8:pos + 12])[0]
        recs.append(data[pos:pos + 16 + incl])
        pos += 16 + incl
    return data[:24], recs


def nmea(body):
    c = 0
    for ch in body.encode():
        c ^= ch
    return "$%s*%02X\r\n" % (body, c)


def main():
    if os.path.isdir(CORPUS):
        for h in os.listdir(CORPUS):
            if h != "lcm_decode":
                shutil.rmtree(os.path.join(CORPUS, h))
    data = os.path.join(ROOT, "data")
    # Velodyne packets: the einride VLP-16 packet, one packet of each sample pcap.
    out("velodyne", "vlp16_einride_packet.bin", open(os.path.join(data, "lidar", "vlp16_einride_packet.bin"), "rb").read())
    for name in ("vlp16_sample.pcap", "vlp32c_sample.pcap"):
        hdr, recs = pcap_records(os.path.join(data, "lidar", name), 3)
        out("pcap", name.replace(".pcap", "_3.pcap"), hdr + b"".join(recs))
        rec = recs[-1]
        payload = rec[16 + 42:]  # Ethernet 14 + IPv4 20 + UDP 8
        if len(payload) == 1206:
            out("velodyne", name.replace(".pcap", "_packet.bin"), payload)
    rec = open(os.path.join(data, "lidar", "vlp16_einride_recording.bin"), "rb").read()
    out("pcap", "vlp16_einride_raw_2.bin", rec[:2 * 1206])
    # OSM XML and PBF: a few drivable ways of West Oakland; a slice of Monaco's PBF.
    xml = osm_slice(os.path.join(data, "osm", "west-oakland.osm"), highway, 6, False)
    out("osm_xml", "west_oakland_6ways.osm", xml)
    with tempfile.TemporaryDirectory() as tmp:
        src = os.path.join(tmp, "slice.osm")
        open(src, "wb").write(xml)
        pbf = os.path.join(tmp, "slice.osm.pbf")
        subprocess.run(["osmium", "cat", "-o", pbf, "-f", "pbf", src], check=True)
        out("osm_pbf", "west_oakland_6ways.osm.pbf", open(pbf, "rb").read())
        mon = os.path.join(tmp, "monaco.osm.pbf")
        subprocess.run(["osmium", "extract", "-b", "7.4246,43.7376,7.4251,43.7379", "-s", "complete_ways",
                        "-o", mon, os.path.join(data, "osm", "monaco.osm.pbf")], check=True)
        out("osm_pbf", "monaco_bbox.osm.pbf", open(mon, "rb").read())
        monx = os.path.join(tmp, "monaco.osm")
        subprocess.run(["osmium", "cat", "-o", monx, mon], check=True)
        out("osm_xml", "monaco_bbox.osm", open(monx, "rb").read())
    # Lanelet2: the first lanelets of the Karlsruhe mapping example with their ways and nodes.
    out("lanelet2", "karlsruhe_3lanelets.osm",
        osm_slice(os.path.join(data, "lanelet2", "karlsruhe_mapping_example.osm"), lambda w: True, 3, True))
    out("lanelet2", "karlsruhe_12lanelets.osm",
        osm_slice(os.path.join(data, "lanelet2", "karlsruhe_mapping_example.osm"), lambda w: True, 12, True))
    # NMEA: a GGA/RMC/HDT/VTG epoch stream like a GNSS/INS receiver sends (no NMEA file in data/).
    lines = []
    for i in range(3):
        t = "1234%02d.00" % (10 + i)
        lines.append(nmea("GPGGA,%s,4344.3000,N,00725.4800,E,4,12,0.8,12.3,M,48.1,M,1.0,0000" % t))
        lines.append(nmea("GPRMC,%s,A,4344.3000,N,00725.4800,E,21.4,87.5,231126,,,D" % t))
        lines.append(nmea("HEHDT,87.9,T"))
        lines.append(nmea("GPVTG,87.5,T,,M,21.4,N,39.6,K,D"))
    out("nmea", "epochs.nmea", "".join(lines).encode())
    out("nmea", "mixed.nmea", (nmea("GNGSV,3,1,12,01,40,083,46") + "garbage\r\n" +
                               nmea("GNGGA,235959.50,4344.3000,S,00725.4800,W,1,05,2.5,-3.0,M,0.0,M,,")).encode())
    # YAML: the launch files and the process configs as they are.
    for name in sorted(os.listdir(os.path.join(ROOT, "config", "launch"))):
        out("launch_yaml", name, open(os.path.join(ROOT, "config", "launch", name), "rb").read())
    for name in sorted(os.listdir(os.path.join(ROOT, "config"))):
        p = os.path.join(ROOT, "config", name)
        if name.endswith(".yaml") and os.path.isfile(p):
            out("config_yaml", name, open(p, "rb").read())
    # LCM messages: written by build-fuzz/fuzz_lcm_seeds (fuzz/lcm_seeds.cc).
    gen = os.path.join(ROOT, "build-fuzz", "fuzz_lcm_seeds")
    if os.path.exists(gen):
        d = os.path.join(CORPUS, "lcm_decode")
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        subprocess.run([gen, d], check=True)
    else:
        print("make_seeds: %s not built: fuzz/corpus/lcm_decode left as it is" % gen, file=sys.stderr)


if __name__ == "__main__":
    main()

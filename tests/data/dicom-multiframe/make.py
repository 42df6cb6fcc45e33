#!/usr/bin/env python3
"""Makes this folder's DICOM files from three shared CT slices (needs DCMTK:
dump2dcm, dcmcrle, dcmcjpeg). Run from this folder: python3 make.py

- single/1.dcm, 2.dcm, 3.dcm: 64 x 64 crops (rows and columns 224..288) of
  ../../../../shared/data/volumes/ct-chest-dicom-series-lungpetctdx/1-01, 1-02
  and 1-03.dcm, one frame each, plain attributes (the reference).
- enhanced.dcm: the same three crops as one Enhanced CT image of three
  frames, stored in the order 1-02, 1-01, 1-03, positions, orientation,
  spacing and rescale only in the functional groups (shared and per frame).
- enhanced-rle.dcm, enhanced-jpeg-lossless.dcm: enhanced.dcm compressed.
"""
import os, struct, subprocess, array

SHARED = "../../../../shared/data/volumes/ct-chest-dicom-series-lungpetctdx"
N, R0 = 64, 224
Z = {1: 312, 2: 304, 3: 296}
IPP = "-173.1767578125\\-294.1767578125\\%d"


def crop(k):
    b = open(os.path.join(SHARED, "1-%02d.dcm" % k), "rb").read()
    i = b.index(struct.pack("<HH", 0x7FE0, 0x10) + b"OW", 132)
    px = array.array("H", b[i + 12:i + 12 + 512 * 512 * 2])
    return array.array("H", [px[(R0 + r) * 512 + R0 + c] for r in range(N) for c in range(N)]).tobytes()


HEAD = """(0002,0010) UI =LittleEndianExplicit
(0008,0016) UI [%s]
(0008,0018) UI [1.2.826.0.1.3680043.10.1104.7.%d]
(0008,0060) CS [CT]
(0020,000d) UI [1.2.826.0.1.3680043.10.1104.1]
(0020,000e) UI [1.2.826.0.1.3680043.10.1104.2]
"""
PIX = """(0028,0002) US 1
(0028,0004) CS [MONOCHROME2]
%s(0028,0010) US %d
(0028,0011) US %d
(0028,0100) US 16
(0028,0101) US 12
(0028,0102) US 11
(0028,0103) US 0
"""


def item(lines):
    return ["(fffe,e000) na (Item with undefined length #=1)"] + lines + ["(fffe,e00d) na (ItemDelimitationItem)"]


def seq(tag, items):
    out = ["%s SQ (Sequence with undefined length #=%d)" % (tag, len(items))]
    for it in items:
        out += item(it)
    return out + ["(fffe,e0dd) na (SequenceDelimitationItem)"]


def write(name, text, raw):
    open("frames.raw", "wb").write(raw)
    open("dump.txt", "w").write(text + "(7fe0,0010) OW =frames.raw\n")
    subprocess.run(["dump2dcm", "dump.txt", name], check=True)
    os.remove("frames.raw")
    os.remove("dump.txt")


os.makedirs("single", exist_ok=True)
for k in (1, 2, 3):
    t = HEAD % ("1.2.840.10008.5.1.4.1.1.2", k)
    t += "(0018,0050) DS [8]\n(0020,0032) DS [%s]\n(0020,0037) DS [1\\0\\0\\0\\1\\0]\n" % (IPP % Z[k])
    t += PIX % ("", N, N)
    t += "(0028,0030) DS [0.646484375\\0.646484375]\n(0028,1052) DS [-1024]\n(0028,1053) DS [1]\n"
    write("single/%d.dcm" % k, t, crop(k))

order = (2, 1, 3)
t = HEAD % ("1.2.840.10008.5.1.4.1.1.2.1", 9)
t += PIX % ("(0028,0008) IS [3]\n", N, N)
shared = seq("(0020,9116)", [["(0020,0037) DS [1\\0\\0\\0\\1\\0]"]])
shared += seq("(0028,9110)", [["(0018,0050) DS [8]", "(0028,0030) DS [0.646484375\\0.646484375]"]])
shared += seq("(0028,9145)", [["(0028,1052) DS [-1024]", "(0028,1053) DS [1]", "(0028,1054) LO [HU]"]])
t += "\n".join(seq("(5200,9229)", [shared])) + "\n"
t += "\n".join(seq("(5200,9230)", [seq("(0020,9113)", [["(0020,0032) DS [%s]" % (IPP % Z[k])]]) for k in order])) + "\n"
write("enhanced.dcm", t, b"".join(crop(k) for k in order))
subprocess.run(["dcmcrle", "enhanced.dcm", "enhanced-rle.dcm"], check=True)
subprocess.run(["dcmcjpeg", "enhanced.dcm", "enhanced-jpeg-lossless.dcm"], check=True)

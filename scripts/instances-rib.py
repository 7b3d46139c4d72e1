#!/usr/bin/env python3
"""Writes a RIB scene of N instances of one object (docs/results.md, "instances"): a
subdivided cube with face-varying colours, a trimmed rational NuPatch with vertex colours
and a sphere, placed on a grid with turns and colours of their own.

    instances-rib.py N [--inline] > scene.rib

--inline writes the object's requests out at each instance instead of ObjectInstance (what
an instance means; the same image).
"""
import sys

OBJECT = """\
Translate 0 0 -1
Sphere 0.6 -0.6 0.6 360
TrimCurve [1] [3] [0 0 0 0.25 0.25 0.5 0.5 0.75 0.75 1 1 1] [0] [1] [9] \
 [0.5 0 0 0 0.5 0.707107 1 0.707107 0.5] [1 0.707107 0.5 0 0 0 0.5 0.707107 1] \
 [1 0.707107 1 0.707107 1 0.707107 1 0.707107 1]
NuPatch 3 3 [0 0 0 1 1 1] 0 1 2 2 [0 0 1 1] 0 1 "Pw" [-1 -1 0 1  0 -0.5 0 0.5  1 -1 0 1 \
 -1 1 -0.5 1  0 0.5 -0.25 0.5  1 1 -0.5 1] "vertex color Cs" [1 0 0 0 1 0 0 0 1 1 1 0 0 1 1 1 0 1]
Translate 0 1.5 0 Scale 0.4 0.4 0.4
SubdivisionMesh "catmull-clark" [4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] \
 "P" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1] \
 "facevarying color Cs" [1 0 0 1 0 0 1 0 0 1 0 0  0 1 0 0 1 0 0 1 0 0 1 0 \
 0 0 1 0 0 1 0 0 1 0 0 1  1 1 0 1 1 0 1 1 0 1 1 0  0 1 1 0 1 1 0 1 1 0 1 1 1 0 1 1 0 1 1 0 1 1 0 1]
"""

def main():
    n = int(sys.argv[1])
    inline = "--inline" in sys.argv[2:]
    side = max(1, round(n ** (1 / 3) + 0.5))
    out = sys.stdout
    out.write('Format 320 240 1\nPixelSamples 2 2\nProjection "perspective" "fov" 50\n')
    out.write(f"Translate 0 0 {side * 3.2:.1f}\nWorldBegin\n")
    out.write('LightSource "distantlight" 1 "from" [0 0 0] "to" [0.3 -0.4 1]\n')
    if not inline:
        out.write(f"ObjectBegin 1\n{OBJECT}ObjectEnd\n")
    for i in range(n):
        x, y, z = i % side, i // side % side, i // (side * side)
        c = [(i * 37 % 11) / 10, (i * 17 % 7) / 6, (i * 5 % 13) / 12]
        out.write("AttributeBegin\n")
        out.write(f"Translate {(x - side / 2) * 2.5:.2f} {(y - side / 2) * 2.5:.2f} {z * 2.5:.2f}\n")
        out.write(f"Rotate {i * 23 % 360} 0.3 1 0.2\nColor {c[0]:.2f} {c[1]:.2f} {c[2]:.2f}\n")
        out.write(f"AttributeBegin\n{OBJECT}AttributeEnd\n" if inline else "ObjectInstance 1\n")
        out.write("AttributeEnd\n")
    out.write("WorldEnd\n")

main()

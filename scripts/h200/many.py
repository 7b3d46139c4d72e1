#!/usr/bin/env python3
# many.py OUT NX NY: NX*NY tiny bilinear patches (as field/hostile/many-patches.gen.py, larger).
import sys
out, W, H = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
s = 6.0 / W
with open(out, 'w') as f:
    f.write('Format 640 480 1\nProjection "perspective" "fov" 40\nTranslate 0 0 10\nWorldBegin\n'
            'LightSource "distantlight" 1 "from" [0 0 -1] "to" [0 0 0]\n')
    for j in range(H):
        y = -3 * H / W + j * s
        d = s * 0.5
        f.write(''.join('Patch "bilinear" "P" [%.6f %.6f 0 %.6f %.6f 0 %.6f %.6f 0 %.6f %.6f 0]\n'
                        % (x, y, x + d, y, x, y + d, x + d, y + d)
                        for x in (-3 + i * s for i in range(W))))
    f.write('WorldEnd\n')

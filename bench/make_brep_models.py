#!/usr/bin/env python3
"""Writes the models of bench/check_brep.py into a folder (pure Python, no dependency).

- sphere.json: the exact rational sphere (revolved half circle, poles and a seam);
- inward_sphere.json: the same with u and v swapped (its surface normal points inward);
- closed_tube.json: a closed D-NURBS-style surface, periodic (unclamped uniform knots, wrapped
  control points) along v, with poles at both ends;
- torus.json: the exact torus (two seams, one vertex);
- bent_volume.json: a rational trivariate block (a quarter annulus extruded), 6 faces;
- mirrored_volume.json: the same mirrored (left-handed parametrization, det J < 0);
- sheet.json: an open bicubic sheet (an open shell);
- mixed.json: a curve, the torus and the sheet in one model;
- solid_cylinder.json, solid_ball.json: volumes parametrized by (radius, angles), whose faces
  collapse (the axis, the centre, the poles) or coincide (the angle seam).

Usage: python make_brep_models.py OUT_DIR
"""

import json
import math
import sys
from pathlib import Path

out = sys.argv[1]
Path(out).mkdir(parents=True, exist_ok=True)
h = math.sqrt(0.5)
circ = [(1,0),(1,1),(0,1),(-1,1),(-1,0),(-1,-1),(0,-1),(1,-1),(1,0)]
cw = [1,h,1,h,1,h,1,h,1]
CK = [0,0,0,.25,.25,.5,.5,.75,.75,1,1,1]
def revolve(prof, pw, pk, pdeg, name):
    P = [[[x*a, x*b, z] for (a,b) in circ] for (x,_,z) in prof]
    W = [[w*c for c in cw] for w in pw]
    return {"type":"nurbs-surface","name":name,"degree":[pdeg,2],"knots":[pk,CK],"control_points":P,"weights":W}
r = 1.5
sphere = revolve([(0,0,r),(r,0,r),(r,0,0),(r,0,-r),(0,0,-r)], [1,h,1,h,1], [0,0,0,.5,.5,1,1,1], 2, "sphere")
json.dump(sphere, open(f"{out}/sphere.json","w"))
# closed D-NURBS-like tube, periodic (unclamped uniform) in v with wrapped control points, poles at the ends
n, p = 7, 3
rings = [(0,-2),(1,-1.5),(1.3,0),(0.8,1.4),(0,2)]
P = []
for (rr, z) in rings:
    row = []
    for j in range(n + p):
        a = 2*math.pi*(j % n)/n
        row.append([rr*math.cos(a)*(1+0.1*math.sin(3*a)), rr*math.sin(a), z + 0.1*rr*math.cos(2*a)])
    P.append(row)
kv = [k/(n+2*p) for k in range(n+p+p+1)]
tube = {"type":"nurbs-surface","name":"closed tube","degree":[2,p],"knots":[[0,0,0,1/3,2/3,1,1,1],kv],"control_points":P}
json.dump(tube, open(f"{out}/closed_tube.json","w"))
# a rational bent volume (quarter annulus x height), degree (1,2,1)
Pv = []
Wv = []
for i,rad in enumerate([1.0, 2.0]):
    pl, wl = [], []
    for (x,y),w in zip([(1,0),(1,1),(0,1)],[1,h,1]):
        pl.append([[rad*x, rad*y, 0.0],[rad*x, rad*y, 1.5]]); wl.append([w,w])
    Pv.append(pl); Wv.append(wl)
vol = {"type":"nurbs-volume","name":"bent block","degree":[1,2,1],"knots":[[0,0,1,1],[0,0,0,1,1,1],[0,0,1,1]],"control_points":Pv,"weights":Wv}
json.dump(vol, open(f"{out}/bent_volume.json","w"))

R, rr = 2.0, 0.6
prof = [(R + a*rr, 0, -b*rr) for (a,b) in circ]
torus = revolve(prof, cw, CK, 2, "torus")
json.dump(torus, open(f"{out}/torus.json","w"))
# an open sheet
S = [[[i/3, j/3, 0.1*math.sin(i+j)] for j in range(4)] for i in range(4)]
json.dump({"type":"nurbs-surface","degree":[3,3],"knots":[[0,0,0,0,1,1,1,1]]*2,"control_points":S}, open(f"{out}/sheet.json","w"))
# the sphere with u and v swapped: its surface normal points inward (face written reversed)
sw = dict(sphere); sw["name"] = "inward sphere"
sw["degree"] = sphere["degree"][::-1]; sw["knots"] = sphere["knots"][::-1]
sw["control_points"] = [list(c) for c in zip(*sphere["control_points"])]
sw["weights"] = [list(c) for c in zip(*sphere["weights"])]
json.dump(sw, open(f"{out}/inward_sphere.json","w"))
# the bent volume mirrored (x -> -x): left-handed, det J < 0
mv = json.loads(json.dumps(vol)); mv["name"] = "mirrored block"
for pl in mv["control_points"]:
    for col in pl:
        for pt in col: pt[0] = -pt[0]
json.dump(mv, open(f"{out}/mirrored_volume.json","w"))
# mixed: a curve, the torus, the open sheet
line = {"type":"nurbs-curve","degree":1,"knots":[0,0,1,1],"control_points":[[0,0,5],[1,1,5]]}
json.dump({"entities":[line, torus, json.load(open(f"{out}/sheet.json"))]}, open(f"{out}/mixed.json","w"))
# Volumes with collapsed and coinciding faces, parametrized by (radius, angle, ...): a solid
# cylinder (its r = 0 face is the axis, its two angle faces coincide) and a solid ball (r = 0 is
# the centre, the pole faces are axis segments, the angle faces coincide). vclay drops those
# faces; the rest closes up.
cyl_pts, cyl_w = [], []
for rad in (0.0, 0.5):
    cyl_pts.append([[[rad * a, rad * b, z] for z in (0.0, 2.0)] for (a, b) in circ])
    cyl_w.append([[c, c] for c in cw])
json.dump({"type": "nurbs-volume", "name": "solid cylinder", "degree": [1, 2, 1],
           "knots": [[0, 0, 1, 1], CK, [0, 0, 1, 1]], "control_points": cyl_pts,
           "weights": cyl_w}, open(f"{out}/solid_cylinder.json", "w"))
half = [(0, 1), (1, 1), (1, 0), (1, -1), (0, -1)]  # (distance from axis, z) of a half circle
hw = [1, h, 1, h, 1]
ball_pts, ball_w = [], []
for rad in (0.0, 1.2):
    ball_pts.append([[[rad * x * a, rad * x * b, rad * z] for (a, b) in circ] for (x, z) in half])
    ball_w.append([[wp * c for c in cw] for wp in hw])
json.dump({"type": "nurbs-volume", "name": "solid ball", "degree": [1, 2, 2],
           "knots": [[0, 0, 1, 1], [0, 0, 0, .5, .5, 1, 1, 1], CK], "control_points": ball_pts,
           "weights": ball_w}, open(f"{out}/solid_ball.json", "w"))

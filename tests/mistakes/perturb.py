import csv,sys,random,math
mode=sys.argv[1]; src=sys.argv[2]; dst=sys.argv[3]; seed=int(sys.argv[4]) if len(sys.argv)>4 else 1
rnd=random.Random(seed)
rows=list(csv.DictReader(open(src))); fields=list(rows[0].keys())
if mode=='random-pixels':
    for r in rows: r['u']=repr(rnd.uniform(0,640)); r['v']=repr(rnd.uniform(0,480))
elif mode=='frame-shift':   # tracks one frame off the motion
    top=max(int(r['frame']) for r in rows)
    for r in rows: r['frame']=str(int(r['frame'])+1)
    rows=[r for r in rows if int(r['frame'])<=top]
elif mode=='yaw-degrees':
    for r in rows: r['yaw']=repr(math.degrees(float(r['yaw'])))
elif mode=='yaw-sign':
    for r in rows: r['yaw']=repr(-float(r['yaw']))
w=csv.DictWriter(open(dst,'w',newline=''),fieldnames=fields); w.writeheader(); w.writerows(rows)

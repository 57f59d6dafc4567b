import math, sys
for n in ["crypt","under","ctf3","cornell","demo","crypt64"]:
    rows=[l.split()[1:] for l in open(f'/tmp/cls-{n}.txt')]
    rows=[(int(a),float(b),int(c),float(d)) for a,b,c,d in rows]
    N=len(rows); inv=sum(1 for r in rows if not r[2]); nan=sum(1 for r in rows if math.isnan(r[1]))
    out=[]
    for thr in [0.25,0.35,0.5,0.75]:
        k=[r for r in rows if r[1]>thr]
        out.append(f">{thr}: skip {len(k)} ({len(k)/max(inv,1)*100:.0f}% of invalid), valid {sum(r[2] for r in k)}")
    print(f"{n}: {N} probes, {inv} invalid, unmeasured {nan}; "+"; ".join(out))

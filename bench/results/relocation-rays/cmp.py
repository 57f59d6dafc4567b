import json, subprocess, sys, math, os
env=dict(os.environ, VK_DRIVER_FILES="/usr/share/vulkan/icd.d/lvp_icd.json")
def load(p):
    return json.loads(subprocess.run(["/work/main/build/probebake","inspect",p,"--json"],capture_output=True,text=True,env=env).stdout)
a=load(sys.argv[1]); b=load(sys.argv[2])
pa=a["probe_list"]; pb=b["probe_list"]
same_valid=0; dist=[]; moved_a=moved_b=0; n=len(pa)
for x,y in zip(pa,pb):
    va="valid" in x["flags"]; vb="valid" in y["flags"]
    same_valid+= va==vb
    ra=any(o!=0 for o in x["offset"]); rb=any(o!=0 for o in y["offset"])
    if ra or rb:
        dist.append(math.dist(x["offset"],y["offset"]))
dist.sort()
dv=sorted(math.dist(x["offset"],y["offset"]) for x,y in zip(pa,pb) if "valid" in x["flags"] and "valid" in y["flags"] and (any(x["offset"]) or any(y["offset"])))
qv=lambda f: dv[min(len(dv)-1,int(f*len(dv)))] if dv else 0
print(f"  valid in both and relocated in either: {len(dv)}; offset difference median {qv(0.5):.3f} m, p95 {qv(0.95):.3f} m")
q=lambda f: dist[min(len(dist)-1,int(f*len(dist)))] if dist else 0
print(f"validity agrees {same_valid}/{n} ({100*same_valid/n:.2f}%); probes relocated in either: {len(dist)}; offset difference median {q(0.5):.3f} m, p95 {q(0.95):.3f} m, identical {sum(1 for d in dist if d==0)}")

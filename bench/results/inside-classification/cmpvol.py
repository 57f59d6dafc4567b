import json, subprocess, sys, os
env=dict(os.environ, VK_DRIVER_FILES="/usr/share/vulkan/icd.d/lvp_icd.json")
def load(p): return json.loads(subprocess.run(["/work/main/build/probebake","inspect",p,"--json"],capture_output=True,text=True,env=env).stdout)
a=load(sys.argv[1]); b=load(sys.argv[2])
pa,pb=a["probe_list"],b["probe_list"]
flags_same=sum(1 for x,y in zip(pa,pb) if [f for f in x["flags"] if f!="inside"]==[f for f in y["flags"] if f!="inside"])
sh_valid_same=sum(1 for x,y in zip(pa,pb) if "valid" in x["flags"] and x["sh"]==y["sh"]); nvalid=sum(1 for x in pa if "valid" in x["flags"])
sh_all_same=sum(1 for x,y in zip(pa,pb) if x["sh"]==y["sh"])
inside=sum(1 for y in pb if "inside" in y["flags"])
maxd=max(max(abs(u-v) for u,v in zip(x["sh"],y["sh"])) for x,y in zip(pa,pb))
print(f"flags same (ignoring 'inside') {flags_same}/{len(pa)}; valid probes' SH identical {sh_valid_same}/{nvalid}; all SH identical {sh_all_same}/{len(pa)}; max |dSH| {maxd:g}; inside in B {inside}")

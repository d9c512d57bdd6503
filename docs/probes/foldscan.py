import json,subprocess,sys,os,itertools
env=dict(os.environ,OMP_NUM_THREADS="1",OPENBLAS_NUM_THREADS="1")
# Usage (from the repository root): python3 docs/probes/foldscan.py NAME PRESET.json
# The preset's laid drape from flat at grid 41, seeds 1001 and 1002, over the warp/weft
# ratio, the shear and the bending scale (docs/model-discrepancy.md section 28).
rec=sys.argv[1]; preset=sys.argv[2]
p=json.load(open(preset)); P=p["parameters"]
bw,bf,G=P["bend_warp_Nm"],P["bend_weft_Nm"],P["shear_N_m"]
gm=(bw*bf)**0.5
print(rec,"fitted",bw,bf,G,flush=True)
def run(w,f,g,seed):
    cmd=["build/bin/drape","simulate","--fabric",preset,"--sample-diameter","300mm","--disc-diameter","150mm","--grid","41","--seed",str(seed),"--json",
         "--set",f"bend_warp_Nm={w}","--set",f"bend_weft_Nm={f}","--set",f"shear_N_m={g}"]
    d=json.loads(subprocess.run(cmd,capture_output=True,text=True,env=env).stdout)
    return "%.1f(%d)"%(d["drape_coefficient_percent"],d["node_count"])
for ratio in [1.0, 3.0, 1/3.0]:
  for g in [G/4, G, 4*G, 2000/2.6]:
    for sc in [0.6, 1.0, 1.6]:
      w=gm*sc*ratio**0.5; f=gm*sc/ratio**0.5
      print(rec, "ratio %.2f G %.1f scale %.1f:"%(ratio,g,sc), run(w,f,g,1001), run(w,f,g,1002), flush=True)

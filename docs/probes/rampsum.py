import sys,json,re
meas={}
for i in range(1,11):
    m=json.load(open('/work/shared/data/drape-lab/set-a/DL-A%02d/meta.json'%i))
    meas['DL-A%02d'%i]=m.get('lab_drape_coefficient_percent')
nodes={'DL-A01':6,'DL-A02':8,'DL-A03':8,'DL-A04':8,'DL-A05':5,'DL-A06':7,'DL-A07':6,'DL-A08':6,'DL-A09':5,'DL-A10':6}
res={}
for f in sys.argv[1:]:
    for line in open(f):
        m=re.search(r'(DL-A\d+).json s0 ([\d.]+): D ([\d.]+) nodes (\d+)',line)
        if m: res.setdefault(float(m.group(2)),{})[m.group(1)]=(float(m.group(3)),int(m.group(4)))
for s0,d in sorted(res.items()):
    ok=[r for r,(D,n) in d.items() if abs(D-meas[r])<=2 and abs(n-nodes[r])<=1]
    okn=[r for r,(D,n) in d.items() if abs(n-nodes[r])<=1]
    mae=sum(abs(D-meas[r]) for r,(D,n) in d.items())/len(d)
    print(f"| {s0} | {len(ok)} | {len(okn)} | {mae:.2f} | " + ' | '.join(f'{D:.1f} ({n})' for r,(D,n) in sorted(d.items())) + ' |')

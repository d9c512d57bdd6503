# A waviness that scales with the specimen's bending length c = (B / (rho_A g))^(1/3):
# amplitude = a0 * (c / 20 mm)^p, B the geometric mean of the 6 mm presets' bendings (after the
# calibration from flat on A01, A06, A09; the contours' optimum gives the same tables).
# No new drapes: each record's seven drapes from flat are taken from the fixed waviness
# (1/3/6/10 mm, folders pL of fitall.sh + seeds.sh) nearest in log to the rule's amplitude;
# in-sample loss per rule, then leave-one-out over (a0, p) as pooled.py does for one value.
# python3 docs/probes/waviness_scaled.py FOLDER   (FOLDER holds p1, p3, p6, p10)
import json,math,sys
S=(sys.argv[1] if len(sys.argv)>1 else '.').rstrip('/')+'/'
Ls=['1','3','6','10']
ids=['DL-A%02d'%i for i in range(1,11)]
lab={}; dr={}; c={}
for L in Ls:
  for id in ids:
    f=json.load(open(S+'p%s/%s.fit.json'%(L,id))); r=f['fit']['records'][0]
    lab[id]=(r['measured_drape_coefficient_percent'],r['measured_node_count'])
    out=[]
    for fn in ['flat41','flat61','flat81','flat41.s2','flat61.s2','flat41.s3','flat61.s3']:
      j=json.load(open(S+'p%s/%s.%s.json'%(L,id,fn))); out.append((j['drape_coefficient_percent'],j['node_count']))
    dr[(L,id)]=out
# bending length of the 6 mm preset
for id in ids:
  p=json.load(open(S+'p6/%s.json'%id))
  q=p['parameters']; bw=q['bend_warp_Nm']; bf=q['bend_weft_Nm']; rho=q['areal_density_kg_m2']
  c[id]=((bw*bf)**0.5/(rho*9.81))**(1/3)*1000
def loss(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0)/2+abs(n-N) for a,n in d)/len(d)
def frac(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0)<=2 and abs(n-N)<=1 for a,n in d)/len(d)
def mdD(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0) for a,n in d)/len(d)
def mdn(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(n-N) for a,n in d)/len(d)
def snap(a): return min(Ls,key=lambda L: abs(math.log(a/float(L))))
rules=[(a0,p) for a0 in [1,2,3,4,5,6,8,10] for p in [0,1,2,3]]
def L_of(rule,id): a0,p=rule; return snap(a0*(c[id]/20.0)**p)
def tot(rule,excl=None,f=loss): return sum(f(L_of(rule,j),j) for j in ids if j!=excl)
for p in [0,1,2,3]:
  for a0 in [1,2,3,4,5,6,8,10]:
    r=(a0,p); print('a0 %2d p %d: loss %.3f |dD| %.2f |dn| %.2f within %.0f%%  '%(a0,p,tot(r)/10,tot(r,f=mdD)/10,tot(r,f=mdn)/10,10*tot(r,f=frac)),' '.join(L_of(r,j) for j in ids))
for fam in [[0],[1],[2],[3],[0,1,2,3]]:
  rs=[r for r in rules if r[1] in fam]
  hl=hd=hn=hf=0; ch=[]
  for id in ids:
    b=min(rs,key=lambda r: tot(r,id)); ch.append(b)
    L=L_of(b,id); hl+=loss(L,id); hd+=mdD(L,id); hn+=mdn(L,id); hf+=frac(L,id)
  print('family p in',fam,'LOO held-out loss %.3f |dD| %.2f |dn| %.2f within %.0f%%'%(hl/10,hd/10,hn/10,10*hf),ch)
print({k:round(v,1) for k,v in c.items()})

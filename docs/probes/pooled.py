# Pooled over seeds: seed 1 at grids 41/61/81 (fitall.sh) and seeds 2, 3 at 41/61 (seeds.sh)
import json,sys  # run in the folder that holds fitall.sh's pL folders
Ls=(sys.argv[1] if len(sys.argv)>1 else '1,3,6,10').split(',')
ids=['DL-A%02d'%i for i in range(1,11)]
lab={}; dr={}
for L in Ls:
  for id in ids:
    f=json.load(open('p%s/%s.fit.json'%(L,id))); r=f['fit']['records'][0]
    lab[id]=(r['measured_drape_coefficient_percent'],r['measured_node_count'])
    out=[]
    for fn in ['flat41','flat61','flat81','flat41.s2','flat61.s2','flat41.s3','flat61.s3']:
      try: j=json.load(open('p%s/%s.%s.json'%(L,id,fn))); out.append((j['drape_coefficient_percent'],j['node_count'],fn))
      except Exception: pass
    dr[(L,id)]=out
def loss(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0)/2+abs(n-N) for a,n,_ in d)/len(d)
def frac(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0)<=2 and abs(n-N)<=1 for a,n,_ in d)/len(d)
def mdD(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(a-D0) for a,n,_ in d)/len(d)
def mdn(L,id): D0,N=lab[id]; d=dr[(L,id)]; return sum(abs(n-N) for a,n,_ in d)/len(d)
Ls=[L for L in Ls if all(len(dr[(L,i)])==7 for i in ids)]
print('labels with all 7 drapes:',Ls)
for id in ids:
  print('%s lab %.1f(%d) '%(id,*lab[id])+' | '.join('%s: %s ok %.0f%%'%(L,' '.join('%.1f(%d)'%(a,n) for a,n,_ in dr[(L,id)]),100*frac(L,id)) for L in Ls))
for L in Ls:
  print('%smm pooled: loss %.3f |dD| %.2f |dn| %.2f drapes within 2/1 %.0f%%'%(L,sum(loss(L,i) for i in ids)/10,sum(mdD(L,i) for i in ids)/10,sum(mdn(L,i) for i in ids)/10,100*sum(frac(L,i) for i in ids)/10))
ch=[]; hl=[]; hd=[]; hn=[]; hf=[]
for id in ids:
  b=min(Ls,key=lambda L: sum(loss(L,j) for j in ids if j!=id)); ch.append(b)
  hl.append(loss(b,id)); hd.append(mdD(b,id)); hn.append(mdn(b,id)); hf.append(frac(b,id))
print('LOO choices',ch,'held-out loss %.3f |dD| %.2f |dn| %.2f drapes within 2/1 %.0f%%'%(sum(hl)/10,sum(hd)/10,sum(hn)/10,100*sum(hf)/10))

import json,sys
exec(open('laytab.py').read().split("ids=sorted(lab)")[0])
ids=sorted(lab); Ls=['0.2','0.3','0.4','0.5','1']; grids=[41,61,81]
res={}
for L in Ls:
  for g in grids:
    for id in ids:
      j=json.load(open('lay/%s.g%d.L%s.json'%(id,g,L))); res[(L,g,id)]=(j['drape_coefficient_percent'],j['node_count'])
def loss(L,id): # mean over grids of |dD|/2 + |dn|
    D,N=labDN(id); return sum(abs(res[(L,g,id)][0]-D)/2+abs(res[(L,g,id)][1]-N) for g in grids)/3
def dD(L,id): D,N=labDN(id); return sum(abs(res[(L,g,id)][0]-D) for g in grids)/3
for crit,name in ((loss,'|dD|/2+|dn|'),(dD,'|dD|')):
  ch=[];hd=[];hn=[];ok=[]
  for i,id in enumerate(ids):
    best=min(Ls,key=lambda L: sum(crit(L,j) for j in ids if j!=id)); ch.append(best)
    D,N=labDN(id)
    hd.append(dD(best,id)); hn.append(sum(abs(res[(best,g,id)][1]-N) for g in grids)/3)
    ok.append(all(abs(res[(best,g,id)][0]-D)<=2 and abs(res[(best,g,id)][1]-N)<=1 for g in grids))
  print(name,'choices',ch,'held-out mean|dD| %.2f mean|dn| %.2f within2/1 at all grids %d'%(sum(hd)/10,sum(hn)/10,sum(ok)))
for L in Ls:
  print(L,'all-records loss %.3f |dD| %.2f |dn| %.2f within2/1 all grids %d'%(sum(loss(L,i) for i in ids)/10, sum(dD(L,i) for i in ids)/10,
     sum(sum(abs(res[(L,g,i)][1]-labDN(i)[1]) for g in grids)/3 for i in ids)/10,
     sum(all(abs(res[(L,g,i)][0]-labDN(i)[0])<=2 and abs(res[(L,g,i)][1]-labDN(i)[1])<=1 for g in grids) for i in ids)))

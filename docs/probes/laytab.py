import json,glob,os,sys,itertools
S='/work/shared/data/drape-lab/set-a'
lab={}
for r in sorted(glob.glob(S+'/DL-A*')):
    m=json.load(open(r+'/meta.json'))
    id=os.path.basename(r)
    # lab D and nodes from the fit json's record summary
    f=json.load(open('/work/exp/s9/fits/corr_c41/%s.fit.json'%id))
    lab[id]=f
def labDN(id):
    f=lab[id]
    r=f['fit']['records'][0]
    return r['measured_drape_coefficient_percent'], r['measured_node_count']
ids=sorted(lab)
Ls=sys.argv[1].split(',') if len(sys.argv)>1 else ['0.2','0.3','0.4','1']
grids=[41,61,81]
res={}
for L in Ls:
  for g in grids:
    for id in ids:
      fn='lay/%s.g%d.L%s.json'%(id,g,L)
      try: j=json.load(open(fn)); res[(L,g,id)]=(j['drape_coefficient_percent'],j['node_count'],j['wall_seconds'],j.get('converged'))
      except Exception: pass
for L in Ls:
  print('laying',L)
  for id in ids:
    D,N=labDN(id)
    row=[res.get((L,g,id)) for g in grids]
    print(' %s lab %.1f (%d) | '%(id,D,N)+' | '.join('%.2f (%d)'%(r[0],r[1]) if r else '-' for r in row))
  for g in grids:
    e=[abs(res[(L,g,id)][0]-labDN(id)[0]) for id in ids if (L,g,id) in res]
    ok=[abs(res[(L,g,id)][0]-labDN(id)[0])<=2 and abs(res[(L,g,id)][1]-labDN(id)[1])<=1 for id in ids if (L,g,id) in res]
    nk=[abs(res[(L,g,id)][1]-labDN(id)[1])<=1 for id in ids if (L,g,id) in res]
    if e: print('  grid %d: n=%d mean|dD| %.2f within2/1 %d nodes within1 %d'%(g,len(e),sum(e)/len(e),sum(ok),sum(nk)))
# LOO per grid
for g in grids:
  if not all((L,g,id) in res for L in Ls for id in ids): continue
  err={L:[abs(res[(L,g,id)][0]-labDN(id)[0]) for id in ids] for L in Ls}
  loo=[];ch=[]
  for i in range(len(ids)):
    best=min(Ls,key=lambda L: sum(err[L][j] for j in range(len(ids)) if j!=i))
    loo.append(err[best][i]); ch.append(best)
  print('grid %d LOO held-out mean |dD| %.2f (choices %s) vs laying 1: %.2f'%(g,sum(loo)/len(loo),','.join(ch),sum(err['1'])/len(ids)))

import json,sys
for name in ['crypt','under','ctf3','cornell','demo','crypt1']:
    d=json.load(open(name+'.json'))
    valid={p['index']:('valid' in p['flags']) for p in d['probe_list']}
    f1={}
    for l in open(name+'.it1'):
        g,f,nb=l.split(); f1[int(g)]=float(f)
    row=[name, 'probes %d'%len(valid), 'invalid %d'%sum(1 for v in valid.values() if not v)]
    for X in [0.5,0.6,0.7,0.8,0.9,0.95,1.0]:
        sel=[g for g,f in f1.items() if f>=X-1e-9]
        nv=sum(1 for g in sel if valid[g])
        row.append('>=%.2f: %d (valid %d)'%(X,len(sel),nv))
    print(' | '.join(row))

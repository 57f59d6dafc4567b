import heapq
for n in ["oacmpdm1","cornell","demo"]:
    c = list(open(f"/tmp/counts_{n}.bin","rb").read())
    rpp=256; P=len(c)//rpp
    out=[]
    for K in [1,2,4,8,16,32]:
        tot=0; tot2=0; work=sum(c)
        for p in range(P):
            pr=c[p*rpp:(p+1)*rpp]
            for b0 in range(0,rpp,8*K):
                blk=pr[b0:b0+8*K]
                lanes=[sum(blk[k*8+l] for k in range(K)) for l in range(8)]
                tot+=max(lanes)*8
                h=[0]*8
                for x in blk:
                    t=heapq.heappop(h); heapq.heappush(h,t+x)
                tot2+=max(h)*8
        out.append(f"K={K}: st {work/tot:.3f} dyn {work/tot2:.3f}")
    print(n, "; ".join(out))

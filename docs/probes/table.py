import json, sys, os
label = sys.argv[1]
rows = []; ok14 = ok15 = fitok = spread_ok = 0; n = 0; mesh = []; held = []
print(f"| record | wall [s] | chi2/dof | D / nodes measured | fitted D (nodes) | B warp / weft [N*m] | from flat 41 / 61 / 81: D (nodes) | spread | fitted ok | flat ok (41-81) |")
print("|---|---|---|---|---|---|---|---|---|---|")
for i in range(1, 11):
    rid = f"DL-A{i:02d}"
    try:
        d = json.load(open(f"{label}/{rid}.fit.json"))
    except Exception as e:
        continue
    n += 1
    f = d["fit"]; r = f["records"][0]
    t = open(f"{label}/{rid}.time").read().strip()
    P = d["parameters"]
    bw = P.get("bend_warp_Nm"); bf = P.get("bend_weft_Nm")
    if isinstance(bw, dict): bw = bw.get("value"); bf = bf.get("value")
    Dm = r["measured_drape_coefficient_percent"]; nm = r["measured_node_count"]
    Df = r["fitted_drape_coefficient_percent"]; nf = r["fitted_node_count"]
    flat = []
    for g in (41, 61, 81):
        try:
            s = json.load(open(f"{label}/{rid}.flat{g}.json")); flat.append((s["drape_coefficient_percent"], s["node_count"], s["converged"]))
        except Exception:
            flat.append(None)
    fitted_ok = abs(Df - Dm) <= 2 and abs(nf - nm) <= 1
    fl = [x for x in flat if x]
    flat_ok = len(fl) == 3 and all(abs(x[0] - Dm) <= 2 and abs(x[1] - nm) <= 1 for x in fl)
    sp = max(x[0] for x in fl) - min(x[0] for x in fl) if fl else float('nan')
    if len(fl) == 3: mesh.append(sp); held.append(abs(fl[1][0] - Dm))
    ok14 += all(abs(x[0] - Dm) <= 2 for x in fl) and len(fl) == 3
    fitok += fitted_ok; ok15 += fitted_ok and flat_ok
    spread_ok += len(fl) == 3 and sp <= 1 and max(x[1] for x in fl) - min(x[1] for x in fl) <= 1
    fs = " / ".join(f"{x[0]:.2f} ({x[1]}){'' if x[2] else ' not at rest'}" if x else "-" for x in flat)
    print(f"| {rid} | {float(t):.0f} | {f['chi2']:.1f}/{f['dof']} | {Dm} / {nm:.0f} | {Df:.1f} ({nf:.1f}) | {bw:.2g} / {bf:.2g} | {fs} | {sp:.2f} | {'yes' if fitted_ok else 'no'} | {'yes' if flat_ok else 'no'} |")
print()
print(f"{n} records: fitted within 2/1: {fitok}; from flat D within 2 of the record at 41, 61 and 81: {ok14}; spread <=1 and nodes within 1 over 41-81: {spread_ok}; fitted and from flat (D 2, nodes 1) at all three grids: {ok15}")
if mesh: print(f"mean spread over 41-81 {sum(mesh)/len(mesh):.2f} (max {max(mesh):.2f}); mean |D61 - Dmeas| {sum(held)/len(held):.2f}")

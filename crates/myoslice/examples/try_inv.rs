use myoslice::prelude::*;
fn main() -> Result<()> {
    let mut sim = Simulation::phantom(SimulationConfig::default())?;
    sim.set_knee(90f64.to_radians(), 0.0)?;
    let lat = sim.lattice().clone();
    let t = sim.tissue().unwrap();
    let m = sim.tissue_metrics().unwrap();
    let k = sim.skeleton().knee().point;
    let mut n = 0;
    for (e, r) in m.volume_ratio.iter().enumerate() {
        if *r > 0.0 || n >= 2 {
            continue;
        }
        n += 1;
        let h = lat.fat.hexes[e];
        println!("element {e} ratio {r:.2}");
        for &v in &h {
            let v = v as usize;
            let l = v % (lat.fat.layers + 1);
            let sj = v / (lat.fat.layers + 1);
            let (s, j) = (sj / lat.fat.rays, sj % lat.fat.rays);
            let c = if l == 0 {
                format!(
                    "{:?} ref {:?}",
                    lat.fat.inner_contact[sj],
                    lat.fat_muscle_ref[sj].map(|(mi, _)| lat.muscles[mi as usize].name.clone())
                )
            } else {
                String::new()
            };
            let d = t.fat.x[v] - lat.fat.vertices[v];
            println!(
                "  v{v} s{s} j{j} l{l} rest {:?} moved {:?} {c}",
                (lat.fat.vertices[v] - k) * 100.0,
                d * 100.0
            );
        }
    }
    Ok(())
}

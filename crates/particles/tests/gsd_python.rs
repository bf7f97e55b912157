//! Our GSD files are read by the field's own reader, the `gsd` Python package (as HOOMD-blue,
//! freud and OVITO read them). Skips with a notice when Python or `gsd` is absent, fails then
//! where `COLLOIDSIM_REQUIRE_TOOLS` is set (CI).

use colloidsim_particles::gsd::GsdWriter;
use colloidsim_particles::{Particles, SimBox};
use std::process::Command;

fn python_has_gsd() -> bool {
    colloidsim_core::tools::python_module_or_skip("gsd.hoomd", "python_gsd_reads_our_trajectories")
}

#[test]
fn python_gsd_reads_our_trajectories() {
    if !python_has_gsd() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("traj.gsd");
    let sbox = SimBox::new([10.0, 12.0, 14.0]);
    let mut p = Particles::monodisperse(
        vec![[0.5, -1.25, 3.0], [4.0, 5.5, -6.75], [-4.5, 0.0, 6.5]],
        1.0,
    );
    p.type_names = vec!["A".into(), "Big".into()];
    p.typeid = vec![0, 1, 0];
    p.diameter = vec![1.0, 2.5, 1.0];
    p.image = vec![[0, 0, 0], [1, -1, 2], [0, 3, 0]];
    {
        let mut w = GsdWriter::create_new(&path).unwrap();
        w.write_frame(0, &sbox, &p, false, &[("droplet/radius", 7.5)])
            .unwrap();
        p.pos[0][0] = 1.5;
        w.write_frame(100, &sbox, &p, true, &[("droplet/radius", 7.0)])
            .unwrap();
    }
    let script = r#"
import sys, gsd.hoomd, numpy as np
with gsd.hoomd.open(sys.argv[1], "r") as t:
    assert len(t) == 2, len(t)
    f0, f1 = t[0], t[1]
    assert f1.configuration.step == 100
    assert np.allclose(f1.configuration.box, [10, 12, 14, 0, 0, 0])
    assert f1.configuration.dimensions == 3
    assert f1.particles.N == 3
    assert list(f1.particles.types) == ["A", "Big"], f1.particles.types
    assert list(f1.particles.typeid) == [0, 1, 0]
    assert np.allclose(f1.particles.diameter, [1.0, 2.5, 1.0])
    assert np.allclose(f1.particles.position, [[1.5, -1.25, 3.0], [4.0, 5.5, -6.75], [-4.5, 0.0, 6.5]])
    assert np.allclose(f0.particles.position[0], [0.5, -1.25, 3.0])
    assert (f1.particles.image == [[0, 0, 0], [1, -1, 2], [0, 3, 0]]).all()
    assert np.isclose(f0.log["droplet/radius"][0], 7.5) and np.isclose(f1.log["droplet/radius"][0], 7.0)
    assert np.allclose(f1.log["particles/position_f64"][0], [1.5, -1.25, 3.0])
print("ok")
"#;
    let out = Command::new("python3")
        .args(["-c", script, path.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("ok"),
        "python gsd could not read our file:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

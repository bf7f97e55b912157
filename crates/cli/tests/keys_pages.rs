//! `docs/keys/METHOD.md` is what `colloidsim keys METHOD --format markdown` prints, for every
//! registered method: the reference pages are generated from the keys' declarations and cannot
//! drift from them. After changing a key, write the pages again with
//! `for m in bcd droplet-bd bd dpd hs-mc mpcd droplet-mpcd; do colloidsim keys $m --format markdown > docs/keys/$m.md; done`.

use std::path::Path;
use std::process::Command;

#[test]
fn every_key_page_is_what_the_binary_prints() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/keys");
    let mut pages = 0;
    for m in colloidsim_run::registry::all() {
        let name = m.names()[0];
        let o = Command::new(env!("CARGO_BIN_EXE_colloidsim"))
            .args(["keys", name, "--format", "markdown"])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let path = docs.join(format!("{name}.md"));
        let page = std::fs::read_to_string(&path).unwrap_or_else(|e| {
            panic!("{}: {e} (write it as the module docs say)", path.display())
        });
        assert!(
            page.as_bytes() == o.stdout.as_slice(),
            "{} differs from `colloidsim keys {name} --format markdown`: write it again (see \
             crates/cli/tests/keys_pages.rs)",
            path.display()
        );
        pages += 1;
    }
    // The pages folder holds no page of a method that is gone.
    let files = std::fs::read_dir(&docs).unwrap().count();
    assert_eq!(
        files, pages,
        "docs/keys holds pages of no registered method"
    );
}

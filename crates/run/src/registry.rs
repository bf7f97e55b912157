//! The one place methods are registered: every method, in the order `--help` lists them.
//! Adding a method is one line here (and its folder under `crate::methods`).

use crate::method::{Method, Scenario};
use anyhow::Result;

/// Every method, in the order `--help` lists them. New methods register here.
static METHODS: &[&dyn Method] = &[
    &crate::methods::bcd::BcdMethod,
    &crate::methods::droplet_bd::DropletBd,
    &crate::methods::bd::BulkBd,
    &crate::methods::dpd::DpdMethod,
    &crate::methods::hs_mc::HsMc,
    &crate::methods::mpcd::MpcdBulk,
    &crate::methods::droplet_mpcd::DropletMpcd,
];

/// Every registered method.
pub fn all() -> &'static [&'static dyn Method] {
    METHODS
}

/// Every `method` value a scenario may name.
pub fn names() -> Vec<&'static str> {
    METHODS
        .iter()
        .flat_map(|m| m.names().iter().copied())
        .collect()
}

/// The method a scenario names.
pub fn find(name: &str) -> Result<&'static dyn Method> {
    METHODS
        .iter()
        .copied()
        .find(|m| m.names().contains(&name))
        .ok_or_else(|| anyhow::anyhow!("unknown method '{name}' (one of: {})", names().join(", ")))
}

/// The method of a scenario, with the scenario named in the error.
pub fn of(sc: &Scenario) -> Result<&'static dyn Method> {
    let name = sc.method()?;
    find(&name).map_err(|e| anyhow::anyhow!("{}: {e}", sc.label()))
}

/// Every method's headline observables ([`Method::headline`]) as the Markdown table of
/// docs/parallel.md ("Headline observables"), generated from the declarations.
pub fn headline_markdown() -> String {
    let mut s = String::from(
        "| method | column | unit | in `summary.json` | what it is |\n|---|---|---|---|---|\n",
    );
    for m in METHODS {
        for h in m.headline() {
            let column = match h.labels {
                None => format!("`{}`", h.name),
                Some(l) => format!("`{}_LABEL` (LABEL from `{l}`)", h.name),
            };
            s.push_str(&format!(
                "| {} | {column} | {} | `{}` | {} |\n",
                m.names()[0],
                h.unit,
                h.path,
                h.doc.replace('|', "\\|")
            ));
        }
    }
    s
}

#[cfg(test)]
mod tests {
    /// docs/parallel.md lists the headline observables as the declarations say (between its
    /// `headline:begin` and `headline:end` marks); `COLLOIDSIM_BLESS=1 cargo test -p
    /// colloidsim-run --lib headline_table` writes it again.
    #[test]
    fn the_headline_table_of_the_docs_is_the_declarations() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/parallel.md");
        let doc = std::fs::read_to_string(&path).unwrap();
        let (begin, end) = ("<!-- headline:begin", "<!-- headline:end -->");
        let a = doc
            .find(begin)
            .expect("docs/parallel.md: no headline:begin mark");
        let a = a + doc[a..].find('\n').unwrap() + 1;
        let b = doc
            .find(end)
            .expect("docs/parallel.md: no headline:end mark");
        let want = super::headline_markdown();
        if std::env::var_os("COLLOIDSIM_BLESS").is_some() {
            std::fs::write(&path, format!("{}{want}{}", &doc[..a], &doc[b..])).unwrap();
            return;
        }
        assert!(
            doc[a..b] == want,
            "docs/parallel.md's headline table differs from the declarations (Method::headline): \
             write it again with COLLOIDSIM_BLESS=1 cargo test -p colloidsim-run --lib \
             headline_table"
        );
    }
}

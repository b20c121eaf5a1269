//! One POV-Ray object, one editable entry: the POV-Ray translation writes a tessellated object
//! (a blob, an isosurface, a mesh, text) as one `[[shapes]]` triangle per facet, each under the
//! comment naming the object's source position (`# scene.pov:4:1`). Opened as it is, a blob
//! would be 10 000 entries of the scene tree, and moving it a batch of 10 000 edits. The editor
//! regroups each such run into an object (`[objects.<name>]`, its triangles as they were) placed
//! once by an `[[instances]]` entry named after the POV-Ray object (`blob (line 4)`): one entry
//! that moves, turns, scales and groups as one, and renders the same (an instance of an object
//! in world coordinates with no transform places its triangles where they were).

use toml_edit::{ArrayOfTables, DocumentMut, Item, Table};

/// Fewest triangles of one source position that become an object (fewer stay shapes).
const MIN_TRIANGLES: usize = 2;

/// `toml` (a POV-Ray translation) with every run of triangle entries of one source object made
/// an object placed once; `source` is the `.pov` text, for the objects' names. Text it cannot
/// read as TOML comes back as it was (the parser then says why).
pub fn regroup(toml: &str, source: Option<&str>) -> String {
    let Ok(mut doc) = toml.parse::<DocumentMut>() else { return toml.to_string() };
    let Some(shapes) = doc.get("shapes").and_then(Item::as_array_of_tables) else { return toml.to_string() };

    // Runs of consecutive triangles under the same source comment
    let origin = |t: &Table| -> Option<String> {
        let prefix = t.decor().prefix()?.as_str()?;
        let line = prefix.lines().map(str::trim).rfind(|l| l.starts_with("# "))?;
        Some(line[2..].to_string())
    };
    let is_triangle = |t: &Table| t.get("type").and_then(Item::as_str) == Some("triangle");
    let tables: Vec<Table> = shapes.iter().cloned().collect();
    let mut runs: Vec<(usize, usize, String)> = Vec::new();
    let mut i = 0;
    while i < tables.len() {
        let Some(key) = origin(&tables[i]).filter(|_| is_triangle(&tables[i])) else {
            i += 1;
            continue;
        };
        let mut j = i + 1;
        while j < tables.len() && is_triangle(&tables[j]) && origin(&tables[j]).as_deref() == Some(key.as_str()) {
            j += 1;
        }
        if j - i >= MIN_TRIANGLES {
            runs.push((i, j, key));
        }
        i = j;
    }
    if runs.is_empty() {
        return toml.to_string();
    }

    // Each run: an object, and an instance placing it
    let mut kept = ArrayOfTables::new();
    let mut instances = doc.get("instances").and_then(Item::as_array_of_tables).cloned().unwrap_or_default();
    let mut objects = doc.get("objects").and_then(Item::as_table).cloned().unwrap_or_else(Table::new);
    objects.set_implicit(true);
    let mut next = 0;
    for (k, table) in tables.iter().enumerate() {
        if !runs.iter().any(|(a, b, _)| (*a..*b).contains(&k)) {
            kept.push(table.clone());
        }
    }
    for (start, end, key) in &runs {
        let position = parse_position(key);
        let base = match position {
            Some((line, col)) => format!("pov_{line}_{col}"),
            None => "pov_object".to_string(),
        };
        let mut name = base.clone();
        while objects.contains_key(&name) {
            next += 1;
            name = format!("{base}_{next}");
        }
        let mut triangles = ArrayOfTables::new();
        for table in &tables[*start..*end] {
            let mut t = table.clone();
            t.decor_mut().clear();
            triangles.push(t);
        }
        let mut object = Table::new();
        object.insert("shapes", Item::ArrayOfTables(triangles));
        objects.insert(&name, Item::Table(object));

        let kind = position.and_then(|(line, col)| source.and_then(|s| word_at(s, line, col)));
        let label = match (kind, position) {
            (Some(kind), Some((line, _))) => format!("{kind} (line {line})"),
            (None, Some((line, _))) => format!("object (line {line})"),
            _ => name.clone(),
        };
        let mut instance = Table::new();
        instance.insert("name", toml_edit::value(label));
        instance.insert("object", toml_edit::value(name.as_str()));
        instance.decor_mut().set_prefix(format!(
            "\n# {key}: {} triangles of one POV-Ray object, placed once (the editor moves it as one)\n",
            end - start
        ));
        instances.push(instance);
    }
    doc.insert("shapes", Item::ArrayOfTables(kept));
    if doc.get("shapes").and_then(Item::as_array_of_tables).is_some_and(|a| a.is_empty()) {
        doc.remove("shapes");
    }
    doc.insert("objects", Item::Table(objects));
    doc.insert("instances", Item::ArrayOfTables(instances));
    doc.to_string()
}

/// `file:line:col` (the file may hold colons) as (line, col).
fn parse_position(key: &str) -> Option<(usize, usize)> {
    let mut parts = key.rsplitn(3, ':');
    let col = parts.next()?.trim().parse().ok()?;
    let line = parts.next()?.trim().parse().ok()?;
    Some((line, col))
}

/// The keyword at `line`:`col` (from 1) of `source`: `blob`, `isosurface`, `mesh`, ...
fn word_at(source: &str, line: usize, col: usize) -> Option<String> {
    let text = source.lines().nth(line.checked_sub(1)?)?;
    let rest: String = text.chars().skip(col.checked_sub(1)?).collect();
    let word: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric() || *c == '_').collect();
    (!word.is_empty() && word.len() <= 32).then_some(word)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRIANGLE: &str = "material = \"m\"\ntype = \"triangle\"\nvertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]\n";

    #[test]
    fn a_run_of_one_objects_triangles_becomes_one_instance() {
        let mut toml = String::from("[materials.m]\ntype = \"diffuse\"\n\n# s.pov:2:1\n[[shapes]]\ntype = \"sphere\"\nmaterial = \"m\"\nradius = 1\n");
        for _ in 0..3 {
            toml += &format!("\n# s.pov:3:5\n[[shapes]]\n{TRIANGLE}");
        }
        toml += &format!("\n# s.pov:9:1\n[[shapes]]\n{TRIANGLE}");
        let out = regroup(&toml, Some("camera {}\nsphere { 0, 1 }\n    blob { threshold 0.5 }\n"));
        let doc: DocumentMut = out.parse().unwrap();
        // The sphere and the lone triangle stay shapes; the three triangles are one object
        assert_eq!(doc["shapes"].as_array_of_tables().unwrap().len(), 2, "{out}");
        assert_eq!(doc["objects"]["pov_3_5"]["shapes"].as_array_of_tables().unwrap().len(), 3, "{out}");
        let instances = doc["instances"].as_array_of_tables().unwrap();
        assert_eq!(instances.len(), 1);
        assert_eq!(instances.get(0).unwrap()["name"].as_str(), Some("blob (line 3)"));
        assert_eq!(instances.get(0).unwrap()["object"].as_str(), Some("pov_3_5"));
    }

    #[test]
    fn text_without_runs_comes_back_as_it_was() {
        let toml = format!("# s.pov:3:5\n[[shapes]]\n{TRIANGLE}");
        assert_eq!(regroup(&toml, None), toml);
        assert_eq!(regroup("not [ toml", None), "not [ toml");
    }
}

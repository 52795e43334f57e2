//! VTK output: an unstructured grid (.vtu, ASCII) of hexahedra with integer node sets and any
//! number of vector fields (displacements, mode shapes), for ParaView.

use super::mesh::Mesh;
use std::fmt::Write as _;
use std::path::Path;

/// A named per-node field: scalars (1 component) or vectors (3 components).
pub struct NodeField<'a> {
    pub name: &'a str,
    pub components: usize,
    pub values: &'a [f64],
}

pub fn write_vtu(
    path: &Path,
    mesh: &Mesh,
    node_sets: &[(&str, Vec<i32>)],
    fields: &[NodeField],
) -> std::io::Result<()> {
    let mut s = String::new();
    let (n, e) = (mesh.nodes.len(), mesh.elements.len());
    writeln!(s, r#"<?xml version="1.0"?>"#).unwrap();
    writeln!(s, r#"<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">"#).unwrap();
    writeln!(s, r#"<UnstructuredGrid><Piece NumberOfPoints="{n}" NumberOfCells="{e}">"#).unwrap();
    writeln!(s, r#"<Points><DataArray type="Float64" NumberOfComponents="3" format="ascii">"#).unwrap();
    for p in &mesh.nodes {
        writeln!(s, "{:e} {:e} {:e}", p[0], p[1], p[2]).unwrap();
    }
    writeln!(s, "</DataArray></Points>").unwrap();
    writeln!(s, r#"<Cells><DataArray type="Int64" Name="connectivity" format="ascii">"#).unwrap();
    for el in &mesh.elements {
        // VTK_HEXAHEDRON numbers its nodes as hex8::NODES does (bottom face, then top).
        writeln!(s, "{}", el.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" ")).unwrap();
    }
    writeln!(s, r#"</DataArray><DataArray type="Int64" Name="offsets" format="ascii">"#).unwrap();
    for i in 1..=e {
        writeln!(s, "{}", 8 * i).unwrap();
    }
    writeln!(s, r#"</DataArray><DataArray type="UInt8" Name="types" format="ascii">"#).unwrap();
    for _ in 0..e {
        writeln!(s, "12").unwrap();
    }
    writeln!(s, "</DataArray></Cells><PointData>").unwrap();
    for (name, values) in node_sets {
        writeln!(s, r#"<DataArray type="Int32" Name="{name}" format="ascii">"#).unwrap();
        for v in values {
            writeln!(s, "{v}").unwrap();
        }
        writeln!(s, "</DataArray>").unwrap();
    }
    for f in fields {
        writeln!(
            s,
            r#"<DataArray type="Float64" Name="{}" NumberOfComponents="{}" format="ascii">"#,
            f.name, f.components
        )
        .unwrap();
        for chunk in f.values.chunks(f.components) {
            writeln!(s, "{}", chunk.iter().map(|v| format!("{v:e}")).collect::<Vec<_>>().join(" ")).unwrap();
        }
        writeln!(s, "</DataArray>").unwrap();
    }
    writeln!(s, "</PointData></Piece></UnstructuredGrid></VTKFile>").unwrap();
    std::fs::write(path, s)
}

//! Print Tables II and III and Fig. 3 at a chosen scale: `cargo run --release -p pf-mpf
//! --example tables -- quick|default|full`.
use pf_mpf::experiments::{Fig3Config, Scale, TableConfig, fig3, table2, table3};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scale: Scale = match std::env::args().nth(1) {
        Some(name) => name.parse()?,
        None => Scale::Quick,
    };
    let cfg = TableConfig::at_scale(scale);
    for (title, rep) in [("Table II", table2(&cfg)?), ("Table III", table3(&cfg)?)] {
        println!(
            "{title} (target {:.4}), paper's values in brackets:",
            rep.target
        );
        for (ours, paper) in rep.table.partitions.iter().zip(&rep.paper.partitions) {
            println!("  {}", ours.against(paper));
        }
    }
    let f = fig3(&Fig3Config::at_scale(scale))?;
    println!("Fig. 3: {:?}", f.calibration);
    for r in &f.rows {
        println!(
            "{}  predicted {:.4}  measured {:.4}  rel {:+.2}",
            r.name, r.predicted_s, r.measured_s, r.rel_error
        );
    }
    Ok(())
}

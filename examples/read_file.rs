//! Read a measurement file as `fit` does and print how many samples it holds: the reading
//! alone, for timing readers (benches/merl_read.sh).
//! Usage: `read_file FILE [CHANNEL]`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = std::path::PathBuf::from(args.next().ok_or("usage: read_file FILE [CHANNEL]")?);
    let opts = goniofit::io::ReadOptions {
        channel: args.next(),
        require_value: true,
        ..Default::default()
    };
    let ds = goniofit::io::read_dataset_columns(&path, &opts)?;
    println!("{} samples", ds.len());
    Ok(())
}

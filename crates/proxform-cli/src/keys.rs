//! `proxform keys`: a swarm's credentials for authenticated flights (`--tls DIR`): a new
//! authority of the swarm's own and, signed by it, the world's, every UAV agent's and an
//! observer's certificate and private key, written into one folder readable by its owner only.
//! Which files go to which machine is in docs/wire.md ("Security").

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Result};

/// Most UAVs given certificates at once (the world's access rules hold a rule per UAV).
pub const MAX_UAVS: u32 = 4096;

/// `proxform keys` arguments.
#[derive(Debug, clap::Args)]
pub struct KeysArgs {
    /// UAVs of the swarm: certificates for UAVs 1 to N (the navigator's is never used to publish).
    #[arg(long, value_parser = clap::value_parser!(u32).range(2..=i64::from(MAX_UAVS)))]
    pub uavs: u32,
    /// The folder to write (made readable by its owner only).
    #[arg(long, default_value = "swarm-keys")]
    pub out: PathBuf,
    /// Host names or addresses the world is reached at, besides localhost and 127.0.0.1
    /// (repeat or separate by commas); agents check the world's certificate against them.
    #[arg(long, value_delimiter = ',')]
    pub host: Vec<String>,
    /// Days the certificates are valid from today (links close when they expire).
    #[arg(long, default_value_t = 365, value_parser = clap::value_parser!(u32).range(1..=3650))]
    pub days: u32,
    /// Replace the credentials a folder already holds (every party then needs the new ones).
    #[arg(long)]
    pub force: bool,
}

/// Writes the swarm's credentials.
#[cfg(feature = "net")]
pub fn run(args: &KeysArgs) -> Result<ExitCode> {
    use anyhow::Context;
    use proxform_net::credentials::{SwarmCredentials, Validity};
    use std::os::unix::fs::{DirBuilderExt, PermissionsExt};

    let ca = args.out.join("ca.pem");
    if std::fs::symlink_metadata(&ca).is_ok() && !args.force {
        bail!("{} already holds a swarm's credentials (use --force to replace them)", args.out.display());
    }
    let today = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .context("the system clock is before 1970")?
        .as_secs()
        / 86_400;
    // From yesterday, so that a peer whose clock is a little behind accepts them.
    let validity = Validity { from_day: today as i64 - 1, days: args.days + 1 };
    let creds = SwarmCredentials::generate("proxform", args.uavs, 0, &args.host, validity)?;
    std::fs::DirBuilder::new()
        .recursive(true)
        .mode(0o700)
        .create(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let meta = std::fs::symlink_metadata(&args.out).with_context(|| args.out.display().to_string())?;
    if !meta.is_dir() {
        bail!("{} is not a folder", args.out.display());
    }
    std::fs::set_permissions(&args.out, std::fs::Permissions::from_mode(0o700))
        .with_context(|| format!("cannot make {} private", args.out.display()))?;
    let write = |name: String, text: &str, mode: u32| -> Result<()> {
        let path = args.out.join(name);
        let mut f = crate::files::create_output(&path)?;
        f.set_permissions(std::fs::Permissions::from_mode(mode))
            .with_context(|| format!("cannot set the mode of {}", path.display()))?;
        std::io::Write::write_all(&mut f, text.as_bytes()).with_context(|| format!("cannot write {}", path.display()))
    };
    write("ca.pem".into(), &creds.ca_pem, 0o644)?;
    write("ca.key".into(), &creds.ca_key_pem, 0o600)?;
    for i in &creds.issued {
        write(format!("{}.pem", i.party.file_stem()), &i.cert_pem, 0o644)?;
        write(format!("{}.key", i.party.file_stem()), &i.key_pem, 0o600)?;
    }
    println!(
        "wrote the swarm's authority and {} certificates (world, uav-1 … uav-{}, observer) to {}, valid {} days; \
         each machine needs ca.pem and its own .pem and .key; keep ca.key offline",
        creds.issued.len(),
        args.uavs,
        args.out.display(),
        args.days
    );
    Ok(ExitCode::SUCCESS)
}

/// Without the network agent there are no authenticated links to make credentials for.
#[cfg(not(feature = "net"))]
pub fn run(_args: &KeysArgs) -> Result<ExitCode> {
    bail!("proxform keys needs a build with the network agent (cargo build --release --features net)")
}
